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

/* Which tool last set the voxels of one 8^3 leaf (tool_marks.c). */
typedef struct fm_tool_leaf {
    int32_t origin[3];
    uint16_t uniform; /* tool slot + 1 of every set voxel while ids is NULL */
    uint64_t set[8];  /* voxel i = 64 x + 8 y + z: bit (i & 63) of set[i >> 6] */
    uint16_t *ids;    /* per voxel slot + 1 (0: never set), once two tools share the leaf */
} fm_tool_leaf;

typedef struct fm_tool_marks {
    int *slot_tool; /* slot -> tool number */
    size_t nslots;
    fm_tool_leaf *leaves; /* dense */
    size_t nleaves, cap_leaves;
    uint32_t *index; /* open addressing over leaf origins: record + 1, 0 = empty */
    size_t index_size; /* power of two, >= 2 * nleaves */
    size_t mixed;      /* records with ids */
} fm_tool_marks;

void fm_tool_marks_free(fm_tool_marks *m);
/* Slot of a tool number (added when new); -1 when out of memory or over
 * FM_STOCK_MAX_TOOLS slots. */
int fm_tool_marks_slot(fm_tool_marks *m, int tool);
/* The voxels in set of the leaf at origin were set by slot's tool.
 * FM_ERR_LIMIT when out of memory (the marks stay consistent). */
fm_status fm_tool_marks_set(fm_tool_marks *m, const int32_t origin[3], const uint64_t set[8],
                            int slot);
/* Forget the leaves inside the index box (no surface there any more). */
void fm_tool_marks_clear(fm_tool_marks *m, const int32_t lo[3], const int32_t hi[3]);
/* 1 and *tool when a cut set voxel ijk, else 0. */
int fm_tool_marks_get(const fm_tool_marks *m, const int32_t ijk[3], int *tool);
size_t fm_tool_marks_bytes(const fm_tool_marks *m);
/* The same without the records' spare capacity (never written, so never
 * resident). */
size_t fm_tool_marks_used_bytes(const fm_tool_marks *m);
/* Snapshot bytes (malloc'd; NULL when out of memory) and back. decode
 * checks every count against the bytes present before allocating and
 * leaves m empty on failure; path names the file in errors. */
unsigned char *fm_tool_marks_encode(const fm_tool_marks *m, size_t *len);
fm_status fm_tool_marks_decode(fm_tool_marks *m, const unsigned char *p, size_t len,
                               const char *path, fm_error *err);

/* The hashes of the stock's open-addressing tables: a 64-bit mixer
 * (MurmurHash3's finalizer) and index triples through it. */
static inline uint64_t fm_stock_hash_mix(uint64_t x)
{
    x ^= x >> 33;
    x *= 0xff51afd7ed558ccdULL;
    x ^= x >> 33;
    x *= 0xc4ceb9fe1a85ec53ULL;
    x ^= x >> 33;
    return x;
}

static inline uint64_t fm_stock_hash3(const int32_t k[3])
{
    return fm_stock_hash_mix(((uint64_t)(uint32_t)k[0] * 0x9E3779B97F4A7C15ULL) ^
                             ((uint64_t)(uint32_t)k[1] << 21) ^
                             ((uint64_t)(uint32_t)k[2] << 42) ^ (uint64_t)(uint32_t)k[2]);
}

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

    fm_tool_marks marks;

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
/* Read and validate an STL file and convert it to a new grid at opt's voxel
 * and band with voxel centres at origin + voxel * i; what ("stock",
 * "design") names it in messages. NULL and err on failure (stl.c). */
fm_vdb *fm_stl_to_vdb(const char *path, const fm_stock_options *opt, const double origin[3],
                      const char *what, fm_error *err);
/* Add removed volume to a tool / block (restoring snapshots uses them). */
fm_status fm_stock_add_tool(fm_stock *s, int tool, double removed);
void fm_stock_add_block(fm_stock *s, int64_t block, double removed, double t0, double t1);

#endif
