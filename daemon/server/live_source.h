/* live_source.h: live mode from an MTConnect source (live_source.c): an
 * adapter's SHDR stream (live_source = shdr://HOST:PORT) or an agent's
 * documents (live_source = mtconnect://HOST:PORT/DEVICE), their data items
 * mapped to the tool tip's X/Y/Z (or with a machine's rotary axes its
 * joints X/Y/Z/A/B/C), the tool, the program line and the spindle speed by
 * live_map, fed to the live job as Modbus positions are (docs/mtconnect.md). */
#ifndef FM_DAEMON_LIVE_SOURCE_H
#define FM_DAEMON_LIVE_SOURCE_H

#include "core/core.h"
#include "jobs.h"

typedef struct fm_live_source_config {
    const char *source;        /* shdr://HOST:PORT or mtconnect://HOST:PORT/DEVICE */
    const char *map;           /* "X=X1actw,Z=Z1actw,tool=p1CurrentTool,line=p1linenumber" */
    const char *machine;       /* the live job's machine file (live_machine): NULL or "" none */
    double scale;              /* mm per source unit: 1, or 25.4 for inches */
    double reconnect_max_s;    /* the longest wait between connection attempts */
} fm_live_source_config;

/* The map's names: X, Y, Z, A, B, C, tool, line, S. Axes not mapped stay
 * at 0; the line and the spindle speed not mapped are not known. */
#define FM_LIVE_MAP_KEYS 9
typedef struct fm_live_map {
    char name[FM_LIVE_MAP_KEYS][64]; /* "" when not mapped */
} fm_live_map;
enum { FM_LIVE_MAP_TOOL = 6, FM_LIVE_MAP_LINE = 7, FM_LIVE_MAP_SPINDLE = 8 };

/* Parse a live_map value; -1 with msg filled when it is wrong. */
int fm_live_map_parse(const char *text, fm_live_map *out, char *msg, size_t msg_size);
/* Are the rotary axes the map names among the machine's (bit 1 << letter
 * of rotary_letters, 0 = A)? -1 with msg filled when not. */
int fm_live_map_check_rotary(const fm_live_map *map, int rotary_letters, const char *machine, char *msg,
                             size_t msg_size);
/* Check a live_source value; -1 with msg filled when it is wrong. */
int fm_live_source_check(const char *source, char *msg, size_t msg_size);

typedef struct fm_live_source fm_live_source;

/* Start the source's thread: it connects (again, with a doubling wait up
 * to reconnect_max_s, said in the live job's status), starts the live job
 * on its first connection, and feeds it positions. */
fm_status fm_live_source_start(const fm_live_source_config *cfg, fm_jobs *jobs, fm_live_source **out,
                               fm_error *err);
void fm_live_source_stop(fm_live_source *source);

#endif
