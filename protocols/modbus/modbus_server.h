/* modbus_server.h: the Modbus/TCP face of frepmill. A machine HMI or PLC
 * reads the simulation's status from a documented register map (version 1,
 * docs/modbus.md) and, when the configuration allows it, sends commands and
 * live axis positions. The server owns its sockets and its thread; it knows
 * nothing of the daemon: the daemon hands it an fm_modbus_service, the small
 * set of calls the register map needs. */
#ifndef FM_MODBUS_SERVER_H
#define FM_MODBUS_SERVER_H

#include <stdint.h>

#include "core/core.h"

/* Version of the register map served at address 0. */
#define FM_MODBUS_MAP_VERSION 1

/* Status bits (register 1). */
#define FM_MODBUS_BIT_JOB_LOADED (1u << 0)
#define FM_MODBUS_BIT_RUNNING (1u << 1)
#define FM_MODBUS_BIT_PAUSED (1u << 2)
#define FM_MODBUS_BIT_DONE (1u << 3)
#define FM_MODBUS_BIT_ERROR (1u << 4)
#define FM_MODBUS_BIT_COLLISION (1u << 5)
#define FM_MODBUS_BIT_LIVE (1u << 6)

/* Commands written to register 100. */
enum {
    FM_MODBUS_CMD_START = 1,  /* start or resume the selected job */
    FM_MODBUS_CMD_PAUSE = 2,  /* pause the selected job */
    FM_MODBUS_CMD_CANCEL = 3, /* cancel the selected job */
    FM_MODBUS_CMD_SELECT = 4  /* select job slot <argument> */
};

/* Error codes shown in register 26 (the list in docs/modbus.md). 2..5 are the
 * fm_status codes of a failed job, so the daemon can pass them through. */
enum {
    FM_MODBUS_ERR_NONE = 0,
    FM_MODBUS_ERR_JOB_INPUT = 2,     /* FM_ERR_INPUT: the program or job spec is wrong */
    FM_MODBUS_ERR_JOB_LIMIT = 3,     /* FM_ERR_LIMIT: a memory or size budget */
    FM_MODBUS_ERR_JOB_IO = 4,        /* FM_ERR_IO: a file or device failed */
    FM_MODBUS_ERR_JOB_INTERNAL = 5,  /* FM_ERR_INTERNAL: a bug */
    FM_MODBUS_ERR_UNKNOWN_COMMAND = 16,
    FM_MODBUS_ERR_NO_JOB = 17,       /* the command needs a job and none is selected */
    FM_MODBUS_ERR_BAD_SLOT = 18,     /* no job in that slot */
    FM_MODBUS_ERR_BAD_STATE = 19,    /* e.g. resume a job that is done */
    FM_MODBUS_ERR_WATCHDOG = 20,     /* the HMI watchdog expired; running jobs were paused */
    FM_MODBUS_ERR_LIVE_REFUSED = 21, /* a live position or live on/off was refused */
    FM_MODBUS_ERR_BUSY = 22          /* the daemon cannot take it now; retry */
};

/* A snapshot of everything the status registers show, filled by the daemon.
 * The server converts the doubles to float32 on the wire. Heartbeat, map
 * version and the acknowledged sequence number belong to the server. */
typedef struct fm_modbus_status {
    uint16_t bits;                /* FM_MODBUS_BIT_* */
    uint32_t block;               /* current block number */
    uint32_t source_line;         /* current source line */
    uint16_t progress_permille;   /* 0..1000 */
    uint16_t tool;                /* active tool number */
    double tool_tip[3];           /* mm */
    double program_time_s;        /* s */
    double removed_mm3;           /* mm^3 */
    double remaining_mm3;         /* mm^3 */
    double removal_rate_mm3_s;    /* mm^3/s */
    uint16_t finding_count;
    uint32_t first_finding_line;
    uint16_t last_error;          /* FM_MODBUS_ERR_* of the job, 0 if none */
    uint16_t selected_slot;
} fm_modbus_status;

/* What the daemon implements. Every call comes from the server's own thread,
 * so each must be safe against the daemon's other threads (take a snapshot
 * under a lock, post to a queue) and must return quickly: the server serves
 * every client from that thread. Calls return FM_OK, or an fm_status with
 * err filled whose reason picks the error code register 26 shows
 * (fm_modbus_error_code). */
typedef struct fm_modbus_service {
    void *ctx;
    /* Fill *out with the current status. Called once per read request. */
    void (*read_status)(void *ctx, fm_modbus_status *out);
    /* FM_MODBUS_CMD_* with the argument register (102). Called once per new
     * sequence number. Only when the config enables commands. */
    fm_status (*command)(void *ctx, int command, uint32_t argument, fm_error *err);
    /* The controller's new tool tip position (mm) and tool number; the daemon
     * treats it as a motion from the previous one. Only in live mode. */
    fm_status (*live_position)(void *ctx, const double xyz[3], int tool, fm_error *err);
    /* Live mode switched on (1) or off (0) by register 117. */
    fm_status (*live_mode)(void *ctx, int on, fm_error *err);
    /* The HMI watchdog (register 103) stopped changing for watchdog_ms: pause
     * every running job. Called once per expiry. */
    void (*watchdog_expired)(void *ctx);
} fm_modbus_service;

/* The register 26 code of a refused call: by its reason "unknown_command"
 * 16, "no_job" (and "not_found") 17, "bad_slot" 18, "bad_state" 19, "busy"
 * 22; other refusals of a live call 21 (live_refused), of a command the
 * fm_status (2..5). */
uint16_t fm_modbus_error_code(const fm_error *err, int live);

typedef enum fm_modbus_word_order {
    FM_MODBUS_WORDS_ABCD = 0, /* high word first (default) */
    FM_MODBUS_WORDS_CDAB = 1  /* low word first */
} fm_modbus_word_order;

enum { FM_MODBUS_LOG_ERROR = 0, FM_MODBUS_LOG_WARN = 1, FM_MODBUS_LOG_INFO = 2, FM_MODBUS_LOG_DEBUG = 3 };

typedef struct fm_modbus_config {
    char listen_addr[64];          /* numeric IPv4 address; "127.0.0.1" by default */
    uint16_t port;                 /* 0 = ephemeral; see fm_modbus_server_port() */
    fm_modbus_word_order word_order;
    int max_connections;           /* further connections are accepted and closed at once */
    int enable_commands;           /* registers 100-103 writable */
    int enable_live;               /* registers 110-117 writable */
    int watchdog_ms;               /* 0 = no HMI watchdog */
    int idle_timeout_ms;           /* close a connection silent this long (0 = never) */
    int frame_timeout_ms;          /* close a connection whose frame takes longer to arrive */
    /* Optional: where the server's messages go (never printed otherwise). */
    void (*log)(void *log_ctx, int level, const char *message);
    void *log_ctx;
} fm_modbus_config;

/* Defaults: 127.0.0.1:1502, ABCD, 16 connections, read-only, no watchdog,
 * 60 s idle timeout, 2 s frame timeout, no log. */
void fm_modbus_config_default(fm_modbus_config *cfg);

typedef struct fm_modbus_server fm_modbus_server;

/* Bind, listen and start the server thread. The service is copied; its ctx
 * must outlive the server. On failure *out is NULL and err says why. */
fm_status fm_modbus_server_start(const fm_modbus_config *cfg, const fm_modbus_service *svc,
                                 fm_modbus_server **out, fm_error *err);

/* The port actually bound (the ephemeral one when cfg->port was 0). */
uint16_t fm_modbus_server_port(const fm_modbus_server *server);

/* Close every connection, join the thread and free the server. NULL is fine.
 * No service call is made after this returns. */
void fm_modbus_server_stop(fm_modbus_server *server);

#endif
