/* config.h: frepmilld's settings: defaults, the config file (key = value
 * lines, deploy/frepmilld.conf documents every key) and the command-line
 * flags that override it. */
#ifndef FM_DAEMON_CONFIG_H
#define FM_DAEMON_CONFIG_H

#include <stddef.h>

typedef struct fm_daemon_config {
    char listen[128];          /* HTTP ADDR:PORT; default 127.0.0.1:8470 */
    char state_dir[1024];      /* default ./frepmilld-state */
    int workers;               /* simulation threads = jobs at once; default 2 */
    int threads_per_job;       /* OpenVDB threads of one job; 0: one per core */
    char modbus_listen[128];   /* ADDR:PORT or "off"; default 127.0.0.1:1502 */
    int modbus_commands;       /* registers 100-103 writable */
    int modbus_live;           /* live mode registers writable */
    int modbus_watchdog_ms;
    char token[128];           /* bearer token for write endpoints */
    char log_file[1024];       /* "" or "-": standard error */
    int log_level;             /* fm_log_level */
    double snapshot_interval_s; /* seconds of work between stock snapshots */
    double publish_interval_s;  /* seconds between mesh chunk publications */
    double mesh_history_mb;     /* earlier chunk meshes kept per job (chunks?at=T) */
    double max_request_mb;
    int max_jobs;              /* jobs kept (all states) */
    double job_memory_mb;      /* grid budget per job */
    int max_connections;
    int max_connections_per_ip;
    int request_deadline_ms;
    int idle_timeout_s;
    char viewer_dir[1024];     /* "" = the built-in default */
    int demo;                  /* submit the bundled demo job at start */
    char demo_dir[1024];       /* where the demo's files are */
    double demo_voxel;
    /* Modbus live mode (docs/modbus.md): the live job's stock, tool table
     * file and voxel; without stock or tools, the selected job's are used. */
    char live_stock[1024];
    char live_tools[1024];
    char live_machine[1024];   /* a machine file: the live job's rotary axes (A/B/C of live_map) */
    double live_voxel;
    double live_feed;          /* mm/min: the program time given to each live move */
    /* G-code: the dialect of jobs (docs/gcode.md: linuxcnc or fanuc) and
     * the server's folders of subprogram files (':'-separated). */
    char dialect[16];
    char subroutine_path[4096];
    /* A Redis Streams job queue shared by several daemons (docs/fleet.md):
     * "" (off) or redis://[user[:password]@]host[:port][/db]. */
    char queue[1024];
    char queue_stream[256];    /* default frepmill:jobs */
    char queue_group[256];     /* default frepmilld */
    char queue_consumer[256];  /* default HOST-PID */
    double queue_claim_s;      /* claim entries idle longer than this; default 30 */
    /* The MTConnect agent under /mtconnect (docs/mtconnect.md). */
    int mtconnect;             /* serve it; default on */
    char mtconnect_device[64]; /* the Device's name; default frepmill */
    char mtconnect_uuid[64];   /* its uuid; default frepmill-HOST */
    char mtconnect_machine[1024]; /* a machine file: its rotary axes join the device */
    int mtconnect_buffer;      /* observations kept; default 16384 */
    int mtconnect_sample_ms;   /* how often the job's status is sampled; default 50 */
    /* Live mode from MTConnect (docs/mtconnect.md): "" (off),
     * shdr://HOST:PORT or mtconnect://HOST:PORT/DEVICE; the data items of
     * X/Y/Z and the tool ("X=Xact,Z=Zact,tool=Tool"); their unit. */
    char live_source[512];
    char live_map[512];
    char live_units[8];        /* mm (default) or inch */
    double live_reconnect_max_s; /* the longest wait between attempts; default 30 */
} fm_daemon_config;

void fm_daemon_config_default(fm_daemon_config *cfg);

/* Apply one setting (a config key or a flag without its dashes). 0 on
 * success, -1 with msg filled. */
int fm_daemon_config_set(fm_daemon_config *cfg, const char *key, const char *value, char *msg,
                         size_t msg_size);

/* Read a config file. 0 on success, -1 with msg ("file:line: ...") filled. */
int fm_daemon_config_load(fm_daemon_config *cfg, const char *path, char *msg, size_t msg_size);

/* Split "ADDR:PORT" (port 0..65535). 0 on success. */
int fm_daemon_split_addr(const char *spec, char *addr, size_t addr_size, unsigned *port);

#endif
