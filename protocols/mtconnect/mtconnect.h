/* mtconnect.h: the MTConnect face of frepmill (docs/mtconnect.md). Two
 * halves that share the standard's vocabulary:
 * - the agent: the daemon's machine as an MTConnect 2.7 device. It keeps a
 *   bounded circular buffer of observations with sequence numbers, fed from
 *   snapshots of what the daemon knows (fm_mtc_service), and answers the
 *   REST protocol's requests (probe, current, sample, assets, asset) with
 *   documents written by libxml2's xmlTextWriter, MTConnectError documents
 *   for bad requests; interval requests become a stream of parts
 *   (multipart/x-mixed-replace) that the HTTP server sends;
 * - the SHDR reader: the adapter protocol a real machine speaks (pipe
 *   delimited observations, multiline assets, conditions, heartbeats),
 *   parsed incrementally with bounded line and asset sizes.
 * The module knows nothing of the daemon or of HTTP: the daemon hands the
 * agent an fm_mtc_service and routes requests to fm_mtc_agent_request. */
#ifndef FM_MTCONNECT_H
#define FM_MTCONNECT_H

#include <stddef.h>
#include <stdint.h>

#include "core/core.h"

/* The namespaces the documents declare (MTConnect 2.7). */
#define FM_MTC_VERSION "2.7.0.0"
#define FM_MTC_NS_DEVICES "urn:mtconnect.org:MTConnectDevices:2.7"
#define FM_MTC_NS_STREAMS "urn:mtconnect.org:MTConnectStreams:2.7"
#define FM_MTC_NS_ASSETS "urn:mtconnect.org:MTConnectAssets:2.7"
#define FM_MTC_NS_ERROR "urn:mtconnect.org:MTConnectError:2.7"

/* -------------------------------------------------------- the service -- */

#define FM_MTC_MAX_ROTARY 3
#define FM_MTC_MAX_FINDINGS 8
#define FM_MTC_MAX_TOOLS 64

/* The device, described once when the agent is made (the probe document). */
typedef struct fm_mtc_device {
    char name[64];                         /* the Device's name; "frepmill" by default */
    char uuid[64];                         /* its uuid */
    int rotary_count;                      /* rotary axes of the machine file, 0..3 */
    char rotary[FM_MTC_MAX_ROTARY];        /* their names: 'A', 'B', 'C' */
} fm_mtc_device;

typedef enum fm_mtc_level {
    FM_MTC_NORMAL = 0,
    FM_MTC_WARNING = 1,
    FM_MTC_FAULT = 2
} fm_mtc_level;

/* A finding of the check, served as a Condition of the Path (MOTION_PROGRAM):
 * its native code is the program line. */
typedef struct fm_mtc_finding {
    fm_mtc_level level;   /* FM_MTC_WARNING or FM_MTC_FAULT (a collision) */
    long line;            /* the program line: the native code */
    char text[160];       /* what was found */
} fm_mtc_finding;

/* Execution states (the standard's EXECUTION values). */
typedef enum fm_mtc_execution {
    FM_MTC_EXEC_UNAVAILABLE = 0,
    FM_MTC_EXEC_READY,
    FM_MTC_EXEC_ACTIVE,
    FM_MTC_EXEC_INTERRUPTED,
    FM_MTC_EXEC_STOPPED,
    FM_MTC_EXEC_PROGRAM_COMPLETED
} fm_mtc_execution;

/* What the daemon knows now. A value the daemon does not know is NAN (for
 * doubles), -1 (line, tool) or "" (program): the agent serves it as
 * UNAVAILABLE. The agent compares each snapshot with the previous one and
 * adds the values that changed to its buffer. */
typedef struct fm_mtc_snapshot {
    int available;                 /* the daemon is serving (AVAILABILITY) */
    fm_mtc_execution execution;
    char program[128];
    long line;                     /* the program line being cut */
    long tool;                     /* the tool number */
    double position[3];            /* X, Y, Z of the tool tip, mm */
    double rotary[3];              /* the joints A, B, C, degrees: the device's rotary axes show theirs */
    double spindle_rpm;            /* the spindle's speed, rev/min */
    double removed_mm3;            /* the stock's removed volume */
    double stock_mm3;              /* the stock's volume now */
    double progress_percent;       /* of the program's time */
    double uncertain_voxels;       /* voxels the cut could not decide */
    char system_fault[160];        /* a failed job's message; "" when none */
    int finding_count;             /* the first FM_MTC_MAX_FINDINGS findings */
    fm_mtc_finding findings[FM_MTC_MAX_FINDINGS];
} fm_mtc_snapshot;

/* A tool of the job's table: a CuttingTool asset. Lengths in mm; NAN when
 * the tool has no such measure. */
typedef struct fm_mtc_tool {
    int number;                /* the table's tool number (the asset is "T<number>") */
    char description[96];
    double diameter;           /* cutting diameter */
    double flute_length;
    double overall_length;     /* flute plus shank, from the tip */
    double corner_radius;
    double shank_diameter;
} fm_mtc_tool;

/* What the daemon implements. Calls come from any thread (the HTTP
 * server's, the agent's own sampler) and must be thread-safe and quick:
 * read published snapshots, never wait for a job. */
typedef struct fm_mtc_service {
    void *ctx;
    /* Fill *out with what is known now; the agent fills it with
     * "unavailable" values before calling. */
    void (*snapshot)(void *ctx, fm_mtc_snapshot *out);
    /* Fill up to cap tools of the current job's table and return how many
     * (0 when there is no job). NULL: no assets. */
    int (*tools)(void *ctx, fm_mtc_tool *out, int cap);
} fm_mtc_service;

/* --------------------------------------------------------- the agent -- */

typedef struct fm_mtc_config {
    fm_mtc_device device;
    char sender[64];              /* the Header's sender; "frepmilld" by default */
    uint32_t buffer_size;         /* observations kept; 4..1048576, default 16384 */
    uint64_t instance_id;         /* 0: the time the agent was made, in seconds */
    int sample_ms;                /* the sampler thread's period; 0: no thread (update on requests) */
} fm_mtc_config;

void fm_mtc_config_default(fm_mtc_config *cfg);

typedef struct fm_mtc_agent fm_mtc_agent;

/* Make the agent (and start its sampler when cfg->sample_ms > 0). The
 * service is copied; its ctx must outlive the agent. */
fm_status fm_mtc_agent_new(const fm_mtc_config *cfg, const fm_mtc_service *svc, fm_mtc_agent **out,
                           fm_error *err);
/* Stop the sampler and free. NULL is fine. */
void fm_mtc_agent_free(fm_mtc_agent *agent);

/* Take a snapshot now and add what changed to the buffer. */
void fm_mtc_agent_update(fm_mtc_agent *agent);

/* The sequence numbers: the first kept, the next to be given. */
void fm_mtc_agent_sequences(fm_mtc_agent *agent, uint64_t *first, uint64_t *next);

typedef struct fm_mtc_stream fm_mtc_stream;

/* The answer to a request. body is malloc'd (the caller frees it), or NULL
 * when stream is set: an interval request, whose parts fm_mtc_stream_read
 * gives until the caller frees the stream. */
typedef struct fm_mtc_reply {
    int status;                /* HTTP status: 200, 400, 404, 405, 406, 500 */
    char content_type[96];     /* "text/xml" or multipart/x-mixed-replace;boundary=... */
    char *body;
    size_t size;
    fm_mtc_stream *stream;
} fm_mtc_reply;

/* Answer GET <root>/<path>?<query>: path is what follows the agent's root
 * ("", "probe", "current", "sample", "assets", "asset/ID", and each of the
 * first three after the device's name, "frepmill/current"); query is the
 * raw query string (percent-encoded, without '?'), may be NULL. Errors are
 * MTConnectError documents with their HTTP status. Returns FM_OK, or an
 * error only when no document could be written (out of memory). */
fm_status fm_mtc_agent_request(fm_mtc_agent *agent, const char *path, const char *query,
                               fm_mtc_reply *out, fm_error *err);

/* The next bytes of a stream: waits up to timeout_ms for the next part (a
 * sample with new observations, or the heartbeat's empty one; a current
 * every interval) and copies at most max bytes. Returns the bytes copied,
 * 0 when nothing is due yet, -1 when the stream ended (the agent is being
 * freed). */
long fm_mtc_stream_read(fm_mtc_stream *stream, char *buf, size_t max, int timeout_ms);
void fm_mtc_stream_free(fm_mtc_stream *stream);

/* ---------------------------------------------------- the query parser -- */

/* The request parameters of the REST protocol. A parameter not given keeps
 * its value from fm_mtc_query_parse's defaults: has_* = 0. */
typedef struct fm_mtc_query {
    int has_from, has_count, has_at, has_interval, has_heartbeat, has_path;
    uint64_t from, at;
    long count;                /* -bufferSize..bufferSize, not 0; default 100 */
    long interval_ms;          /* 0..2^31 ms */
    long heartbeat_ms;         /* 10..600000 ms; default 10000 */
    char path[512];            /* the XPath subset (fm_mtc_path_parse), decoded */
    char type[64];             /* assets: the asset type */
} fm_mtc_query;

/* Parse a raw query string ("from=10&count=5&path=//Linear", percent
 * encoded, '+' a space) of at most 2048 bytes. Unknown parameters, a
 * repeated one, a number out of range or not a number are refused with
 * err's reason the MTConnect error code (QUERY_ERROR, INVALID_REQUEST) and
 * a message naming the parameter. */
fm_status fm_mtc_query_parse(const char *query, size_t len, fm_mtc_query *out, fm_error *err);

/* The XPath subset of the path parameter (docs/mtconnect.md): one or more
 * alternatives joined by '|', each
 *   //E[@attr="v"]...//DataItem[@attr="v"]
 * where E is a component element (Device, Axes, Linear, Rotary, Controller,
 * Path, Spindle... or *) and attr one of id, name, type, subType, category
 * (for DataItem) or id, name (components); at most one component step and
 * one DataItem step, each with at most one predicate. A component step
 * selects every data item inside the components it matches. */
#define FM_MTC_PATH_MAX_ALTS 8
typedef struct fm_mtc_path_step {
    char element[32];          /* "" when the alternative has no such step */
    char attr[16];             /* "" when no predicate */
    char value[64];
} fm_mtc_path_step;
typedef struct fm_mtc_path {
    int count;
    struct {
        fm_mtc_path_step component;
        fm_mtc_path_step item;
    } alt[FM_MTC_PATH_MAX_ALTS];
} fm_mtc_path;

fm_status fm_mtc_path_parse(const char *text, fm_mtc_path *out, fm_error *err);

/* ------------------------------------------------------ the SHDR reader -- */

/* What a key's fields are: a value (key|value), a condition
 * (key|level|nativeCode|nativeSeverity|qualifier|message), a message
 * (key|nativeCode|text). */
typedef enum fm_shdr_kind { FM_SHDR_VALUE = 0, FM_SHDR_CONDITION = 1, FM_SHDR_MESSAGE = 2 } fm_shdr_kind;

typedef struct fm_shdr_observation {
    double timestamp;          /* seconds since 1970 (UTC); NAN when the line had none */
    const char *key;
    fm_shdr_kind kind;
    const char *value;         /* VALUE, MESSAGE: the value ("UNAVAILABLE" kept as is);
                                  CONDITION: the level (NORMAL, WARNING, FAULT, UNAVAILABLE) */
    const char *native_code;   /* CONDITION, MESSAGE; "" otherwise */
    const char *native_severity, *qualifier, *message; /* CONDITION; "" otherwise */
    uint64_t line;             /* the line it came from (1-based) */
} fm_shdr_observation;

typedef struct fm_shdr_asset {
    double timestamp;
    const char *command;       /* "@ASSET@", "@UPDATE_ASSET@", "@REMOVE_ASSET@", "@REMOVE_ALL_ASSETS@" */
    const char *id;            /* asset id, or the type for @REMOVE_ALL_ASSETS@ */
    const char *type;          /* "" when the command has none */
    const char *body;          /* the document (multiline blocks joined with '\n'); "" when none */
    size_t size;
    uint64_t line;             /* the line the command began on */
} fm_shdr_asset;

typedef struct fm_shdr_handlers {
    void *ctx;
    /* How a key's fields are read; NULL: every key is a value, except that
     * a line holding one key whose value is NORMAL, WARNING or FAULT
     * followed by exactly four more fields is a condition. */
    fm_shdr_kind (*kind)(void *ctx, const char *key);
    void (*observation)(void *ctx, const fm_shdr_observation *obs);
    void (*asset)(void *ctx, const fm_shdr_asset *asset);
    /* A protocol line: "* PONG 10000" gives pong_ms = 10000, any other
     * line starting with '*' pong_ms = -1 and its text after the '*' and
     * the spaces that follow it. */
    void (*command)(void *ctx, const char *text, long pong_ms);
    /* A malformed line, skipped: its number, the column (1-based) and why. */
    void (*malformed)(void *ctx, uint64_t line, size_t column, const char *why);
} fm_shdr_handlers;

typedef struct fm_shdr_limits {
    size_t max_line;           /* bytes of one line; default 65536 */
    size_t max_asset;          /* bytes of one multiline asset; default 1 MiB */
    int max_fields;            /* fields of one line; default 4096 */
} fm_shdr_limits;

typedef struct fm_shdr_reader fm_shdr_reader;

/* limits NULL: the defaults. */
fm_shdr_reader *fm_shdr_reader_new(const fm_shdr_limits *limits, const fm_shdr_handlers *handlers);
/* Feed bytes as they arrive; complete lines are handled at once ("\n" or
 * "\r\n"). */
void fm_shdr_reader_feed(fm_shdr_reader *reader, const char *data, size_t size);
/* The input ended: a last line without its newline is handled, an open
 * multiline asset reported malformed. */
void fm_shdr_reader_finish(fm_shdr_reader *reader);
void fm_shdr_reader_free(fm_shdr_reader *reader);

/* ------------------------------------------- an agent's Streams reader -- */

/* The largest Streams document read (an agent's current or sample answer). */
#define FM_MTC_STREAMS_MAX ((size_t)64 << 20)

/* One observation of a Streams document; the strings live for the call. */
typedef struct fm_mtc_observation {
    uint64_t sequence;
    double time;              /* seconds since 1970; NAN when absent or bad */
    const char *name;         /* the data item's name, NULL when absent */
    const char *data_item_id; /* NULL when absent */
    const char *value;        /* the element's text ("" when empty) */
} fm_mtc_observation;

typedef void (*fm_mtc_observation_fn)(void *ctx, const fm_mtc_observation *o);

/* Read an MTConnectStreams document: each observation (an element with a
 * decimal sequence attribute, at any depth) to fn in sequence order, and
 * the header's nextSequence into *next_sequence (left as it is when
 * absent). 0, or -1 with why (not XML: its line and column; another
 * document; over FM_MTC_STREAMS_MAX; out of memory): then fn was not
 * called. (mtc_streams.c) */
int fm_mtc_streams_read(const char *xml, size_t size, fm_mtc_observation_fn fn, void *ctx,
                        uint64_t *next_sequence, char *why, size_t why_size);

/* An SHDR or MTConnect timestamp ("2022-08-08T13:51:34.7167146Z", "Z" or
 * "+hh:mm"; fractions to any length) in seconds since 1970; 0 on success. */
int fm_mtc_parse_time(const char *text, size_t len, double *out);

#endif
