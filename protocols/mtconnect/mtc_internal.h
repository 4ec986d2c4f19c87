/* mtc_internal.h: what the agent's files share (private to
 * protocols/mtconnect): the device model's table of components and data
 * items, the observation record and the document writers. */
#ifndef FM_MTC_INTERNAL_H
#define FM_MTC_INTERNAL_H

#include <pthread.h>

#include "mtconnect.h"

#define MTC_MAX_COMPONENTS 16
#define MTC_MAX_ITEMS 40
#define MTC_MAX_ACTIVE 8   /* active conditions kept per condition data item */
#define MTC_VALUE_MAX 168

typedef struct mtc_component {
    const char *element;       /* Device, Axes, Linear, Rotary, Controller, Path */
    char id[24];
    char name[64];
    int parent;                /* -1 for the Device */
} mtc_component;

typedef enum mtc_category { MTC_SAMPLE = 0, MTC_EVENT = 1, MTC_CONDITION = 2 } mtc_category;

typedef struct mtc_item {
    char id[24];
    char name[32];
    mtc_category category;
    const char *type;          /* POSITION, EXECUTION... */
    const char *sub_type;      /* NULL when none */
    const char *units;         /* NULL when none */
    const char *element;       /* the Streams element: Position, Execution... */
    int component;
} mtc_item;

/* Condition levels of an observation; other categories use LEVEL_VALUE. */
enum { MTC_LEVEL_VALUE = -2, MTC_LEVEL_UNAVAILABLE = -1 };

typedef struct mtc_obs {
    uint64_t seq;              /* 0: none */
    double time;               /* s since 1970 */
    int item;
    int level;                 /* MTC_LEVEL_*, or fm_mtc_level for conditions */
    char native_code[24];
    char value[MTC_VALUE_MAX]; /* the value, or the condition's text */
} mtc_obs;

/* What current shows of one data item. */
typedef struct mtc_state {
    mtc_obs last;              /* the latest value, or a condition's Normal/Unavailable */
    int active_count;
    mtc_obs active[MTC_MAX_ACTIVE];
} mtc_state;

typedef struct mtc_model {
    fm_mtc_device device;
    int component_count, item_count;
    mtc_component components[MTC_MAX_COMPONENTS];
    mtc_item items[MTC_MAX_ITEMS];
} mtc_model;

void mtc_model_build(mtc_model *model, const fm_mtc_device *device);
int mtc_model_find(const mtc_model *model, const char *id);
/* Mark selected[i] for the data items the path selects; -1 with err when
 * it selects none (INVALID_XPATH). */
int mtc_model_select(const mtc_model *model, const fm_mtc_path *path, unsigned char *selected,
                     fm_error *err);

void mtc_state_apply(mtc_state *state, const mtc_obs *obs);

/* The Header's figures. */
typedef struct mtc_header {
    const char *sender;
    uint64_t instance_id;
    uint32_t buffer_size;
    uint64_t first, last, next;
    double model_time;
    int asset_count;
} mtc_header;

void mtc_format_time(double t, char *out, size_t size);
/* A sequence number: decimal digits only, within uint64_t; 0, or -1
 * (mtc_query.c; the query's from/at and a Streams document's sequence and
 * nextSequence). */
int mtc_parse_sequence(const char *text, uint64_t *out);

/* The document writers: a malloc'd document, or NULL when out of memory. */
char *mtc_write_probe(const mtc_model *model, const mtc_header *h, size_t *size);
/* Observations in any order (grouped here by component and category in the
 * model's order, then by sequence). */
char *mtc_write_streams(const mtc_model *model, const mtc_header *h, const mtc_obs *const *obs,
                        size_t count, size_t *size);
char *mtc_write_assets(const mtc_model *model, const mtc_header *h, const fm_mtc_tool *tools,
                       int count, double now, size_t *size);
/* code: the MTConnect error code (QUERY_ERROR...); param: the query
 * parameter an OUT_OF_RANGE names. */
char *mtc_write_error(const mtc_header *h, const char *code, const char *param, const char *uri,
                      const char *message, size_t *size);

#endif
