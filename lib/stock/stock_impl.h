/* stock_impl.h: the fm_stock record and the helpers that lib/stock's own C
 * files (stock.c, stl.c, snapshot.c) share. Nothing outside lib/stock
 * includes it. */
#ifndef FM_STOCK_IMPL_H
#define FM_STOCK_IMPL_H

#include "stock/stock_private.h"

/* Most distinct tool numbers the per-tool table keeps. */
#define FM_STOCK_MAX_TOOLS 4096

typedef struct fm_stock_chunk_slot {
    int32_t key[3];
    int used;
    uint64_t version;
} fm_stock_chunk_slot;

struct fm_stock {
    fm_vdb *vdb;
    fm_stock_options opt;
    uint64_t version;
    double initial_volume;
    double removed_total;

    fm_stock_tool_volume *tools; /* sorted by tool number */
    size_t ntools, cap_tools;

    fm_stock_block *blocks; /* opt.block_table_size entries */
    size_t nblocks;
    uint32_t *block_index; /* open addressing: entry + 1, 0 = empty */
    size_t block_index_size; /* power of two, >= 2 * block_table_size */

    fm_stock_chunk_slot *chunks; /* open addressing, power-of-two size */
    size_t nchunks, cap_chunks;

    char *resume;
};

/* Check opt (NULL: defaults) and fill out with defaults where fields are 0. */
fm_status fm_stock_options_resolve(const fm_stock_options *opt, fm_stock_options *out,
                                   fm_error *err);
/* A stock around a grid already built: tables, initial volume, version 1,
 * every chunk with surface marked. Takes vdb (freed on failure). */
fm_stock *fm_stock_wrap(fm_vdb *vdb, const fm_stock_options *opt, fm_error *err);
/* Mark the chunks an index box touches as changed in version. */
fm_status fm_stock_mark_box(fm_stock *s, const int32_t lo[3], const int32_t hi[3],
                            uint64_t version);
/* Add removed volume to a tool / block (restoring snapshots uses them). */
fm_status fm_stock_add_tool(fm_stock *s, int tool, double removed);
void fm_stock_add_block(fm_stock *s, int64_t block, double removed, double t0, double t1);

#endif
