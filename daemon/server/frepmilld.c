/* frepmilld.c: the frepmill daemon (ARCHITECTURE.md, "The daemon", docs/daemon.md):
 * reads its settings (file, then flags), opens the job store and resumes
 * unfinished jobs, starts the HTTP and Modbus servers, and waits for
 * signals: SIGTERM and SIGINT stop it cleanly (running jobs are
 * snapshotted), SIGHUP reopens the log file. Signals are taken by sigwait
 * in the main thread, so no handler ever runs inside library code. */
#include <errno.h>
#include <limits.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "config.h"
#include "jobs.h"
#include "log.h"
#include "http_service.h"
#include "modbus_service.h"
#include "live_source.h"
#include "mtconnect_service.h"
#include "queue_redis.h"
#include "store.h"

#ifndef FM_SOURCE_DIR
#define FM_SOURCE_DIR "."
#endif
#ifndef FM_BINARY_DIR
#define FM_BINARY_DIR "."
#endif

static void usage(FILE *out)
{
    fprintf(out,
            "usage: frepmilld [--config FILE] [--listen ADDR:PORT] [--state-dir DIR]\n"
            "                 [--workers N] [--modbus-listen ADDR:PORT|off] [--token TOKEN]\n"
            "                 [--log-file FILE] [--log-level error|warn|info|debug]\n"
            "                 [--viewer-dir DIR] [--demo] [--demo-voxel MM]\n"
            "                 [--queue redis://HOST:PORT] [--KEY VALUE]...\n"
            "\n"
            "Every config key (deploy/frepmilld.conf, docs/daemon.md) is also a flag: --KEY\n"
            "VALUE, dashes or underscores. Flags override the config file.\n"
            "--demo submits the bundled demo job (deploy/demo) at start and prints the\n"
            "viewer's URL. Port 0 picks a free port; the address is written to\n"
            "STATE_DIR/http.addr.\n");
}

static void http_log(void *ctx, int level, const char *message)
{
    (void)ctx;
    fm_log((fm_log_level)level, "%s", message);
}

static void modbus_log(void *ctx, int level, const char *message)
{
    (void)ctx;
    fm_log((fm_log_level)level, "%s", message); /* the server names itself */
}

static int file_exists(const char *path)
{
    return access(path, R_OK) == 0;
}

static char *read_text(const char *path)
{
    char *data;
    size_t size;
    fm_error err;
    if (fm_file_read(path, NULL, (size_t)64 << 20, &data, &size, &err) != FM_OK) {
        fm_log(FM_LOG_ERROR, "demo: %s", err.message);
        return NULL;
    }
    return data;
}

/* The bundled demo job, submitted like any client would. */
static int submit_demo(fm_jobs *jobs, const fm_daemon_config *cfg, unsigned port)
{
    char dir[2048], program_path[PATH_MAX], tools_path[PATH_MAX];
    snprintf(dir, sizeof dir, "%s", cfg->demo_dir[0] ? cfg->demo_dir : FM_SOURCE_DIR "/deploy/demo");
    snprintf(program_path, sizeof program_path, "%s/pocket.ngc", dir);
    snprintf(tools_path, sizeof tools_path, "%s/tools.json", dir);
    char *program = read_text(program_path), *tools = read_text(tools_path);
    json_error_t jerr;
    json_t *tools_json = tools ? json_loads(tools, 0, &jerr) : NULL;
    int rc = -1;
    if (program && tools_json) {
        json_t *job = json_pack("{s:s, s:f, s:O, s:{s:s}, s:{s:s}}", "stock",
                                "box:0,0,-30,100,60,0", "voxel", cfg->demo_voxel, "tools",
                                tools_json, "program", "gcode", program, "options", "name", "demo");
        fm_job_doc *doc = NULL;
        fm_error derr;
        fm_error_clear(&derr);
        const fm_job_doc_rules rules = fm_jobs_doc_rules(jobs, 1);
        fm_status st = fm_job_doc_from_json(job, &rules, &doc, &derr);
        json_decref(job);
        char id[64];
        if (st == FM_OK) st = fm_jobs_submit(jobs, doc, id, sizeof id, &derr);
        if (st == FM_OK) {
            char host[64];
            unsigned p;
            fm_daemon_split_addr(cfg->listen, host, sizeof host, &p);
            if (!strcmp(host, "0.0.0.0")) snprintf(host, sizeof host, "127.0.0.1");
            printf("frepmilld: demo job %s submitted\n", id);
            printf("frepmilld: viewer at http://%s:%u/#job=%s\n", host, port, id);
            fflush(stdout);
            rc = 0;
        } else {
            fm_log(FM_LOG_ERROR, "demo: the job was refused: %s", derr.message);
        }
    }
    json_decref(tools_json);
    free(program);
    free(tools);
    return rc;
}

int main(int argc, char **argv)
{
    /* Signals are blocked first, so every thread started later inherits
     * the mask, and taken by sigwaitinfo in the loop at the end. */
    sigset_t signals;
    sigemptyset(&signals);
    sigaddset(&signals, SIGTERM);
    sigaddset(&signals, SIGINT);
    sigaddset(&signals, SIGHUP);
    pthread_sigmask(SIG_BLOCK, &signals, NULL);
    signal(SIGPIPE, SIG_IGN);

    fm_daemon_config cfg;
    fm_daemon_config_default(&cfg);
    char msg[1024];

    /* The config file first, then every flag over it. */
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            usage(stdout);
            return 0;
        }
        if (!strcmp(argv[i], "--config")) {
            if (i + 1 >= argc) {
                fprintf(stderr, "frepmilld: --config needs a file\n");
                return 2;
            }
            if (fm_daemon_config_load(&cfg, argv[i + 1], msg, sizeof msg) != 0) {
                fprintf(stderr, "frepmilld: %s\n", msg);
                return 2;
            }
        }
    }
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "--config")) {
            i++;
            continue;
        }
        if (strncmp(a, "--", 2) != 0 || !a[2]) {
            fprintf(stderr, "frepmilld: unexpected argument '%s'\n", a);
            usage(stderr);
            return 2;
        }
        char key[64];
        snprintf(key, sizeof key, "%s", a + 2);
        for (char *p = key; *p; p++)
            if (*p == '-') *p = '_';
        const char *value;
        if (!strcmp(key, "demo") && (i + 1 >= argc || !strncmp(argv[i + 1], "--", 2))) {
            value = "yes"; /* --demo alone */
        } else {
            if (i + 1 >= argc) {
                fprintf(stderr, "frepmilld: %s needs a value\n", a);
                return 2;
            }
            value = argv[++i];
        }
        if (fm_daemon_config_set(&cfg, key, value, msg, sizeof msg) != 0) {
            fprintf(stderr, "frepmilld: %s\n", msg);
            usage(stderr);
            return 2;
        }
    }

    if (fm_log_open(cfg.log_file, (fm_log_level)cfg.log_level) != 0)
        fprintf(stderr, "frepmilld: cannot open the log file %s; logging to stderr\n",
                cfg.log_file);

    char http_host[64];
    unsigned http_port;
    fm_daemon_split_addr(cfg.listen, http_host, sizeof http_host, &http_port);
    int loopback = fm_http_is_loopback(http_host);
    if (!loopback && !cfg.token[0]) {
        fm_log(FM_LOG_ERROR, "listen %s is not loopback: set a token (--token or the config "
                             "key token) so that write endpoints are protected",
               cfg.listen);
        return 2;
    }

    fm_error err;
    fm_error_clear(&err);
    if (fm_store_mkdirs(cfg.state_dir, &err) != FM_OK) {
        fm_log(FM_LOG_ERROR, "state folder: %s", err.message);
        return 4;
    }
    fm_jobs_config jcfg = {.state_dir = cfg.state_dir,
                           .workers = cfg.workers,
                           .threads_per_job = cfg.threads_per_job,
                           .snapshot_interval_s = cfg.snapshot_interval_s,
                           .publish_interval_s = cfg.publish_interval_s,
                           .mesh_history_bytes = (size_t)(cfg.mesh_history_mb * 1048576.0),
                           .max_jobs = cfg.max_jobs,
                           .job_memory_bytes = (size_t)(cfg.job_memory_mb * 1048576.0),
                           .live_stock = cfg.live_stock,
                           .live_tools = cfg.live_tools,
                           .live_machine = cfg.live_machine,
                           .live_voxel = cfg.live_voxel,
                           .live_feed = cfg.live_feed,
                           .dialect = cfg.dialect,
                           .subroutine_path = cfg.subroutine_path};
    fm_jobs *jobs = fm_jobs_open(&jcfg, &err);
    if (!jobs) {
        fm_log(FM_LOG_ERROR, "cannot open the job store: %s", err.message);
        return 4;
    }

    fm_http_config hcfg;
    fm_http_config_default(&hcfg);
    snprintf(hcfg.listen_addr, sizeof hcfg.listen_addr, "%s", http_host);
    hcfg.port = (uint16_t)http_port;
    snprintf(hcfg.token, sizeof hcfg.token, "%s", cfg.token);
    hcfg.require_token = !loopback;
    hcfg.max_request_bytes = (size_t)(cfg.max_request_mb * 1048576.0);
    hcfg.max_connections = cfg.max_connections;
    hcfg.max_connections_per_ip = cfg.max_connections_per_ip;
    hcfg.request_deadline_ms = cfg.request_deadline_ms;
    hcfg.idle_timeout_s = cfg.idle_timeout_s;
    if (cfg.viewer_dir[0]) {
        snprintf(hcfg.viewer_dir, sizeof hcfg.viewer_dir, "%s", cfg.viewer_dir);
    } else if (file_exists(FM_BINARY_DIR "/viewer/index.html")) {
        snprintf(hcfg.viewer_dir, sizeof hcfg.viewer_dir, "%s", FM_BINARY_DIR "/viewer");
    } else if (file_exists(FM_SOURCE_DIR "/viewer/index.html")) {
        snprintf(hcfg.viewer_dir, sizeof hcfg.viewer_dir, "%s", FM_SOURCE_DIR "/viewer");
    }
    hcfg.log = http_log;
    fm_http_service hsvc;
    fm_jobs_http_service(jobs, &hsvc);
    fm_mtc_agent *mtconnect = NULL;
    if (cfg.mtconnect) {
        if (fm_mtconnect_start(jobs, &cfg, &mtconnect, &err) != FM_OK) {
            fm_log(FM_LOG_ERROR, "mtconnect: %s", err.message);
            fm_jobs_close(jobs);
            return 2;
        }
        fm_mtconnect_mount(mtconnect, &hsvc);
    }
    fm_http_server *http = NULL;
    if (fm_http_server_start(&hcfg, &hsvc, &http, &err) != FM_OK) {
        fm_log(FM_LOG_ERROR, "http: %s", err.message);
        fm_mtconnect_stop(jobs, mtconnect);
        fm_jobs_close(jobs);
        return 4;
    }
    unsigned port = fm_http_server_port(http);
    char addr_line[128];
    int n = snprintf(addr_line, sizeof addr_line, "http://%s:%u\n", http_host, port);
    if (fm_store_write_atomic(cfg.state_dir, "http.addr", addr_line, (size_t)n, &err) != FM_OK)
        fm_log(FM_LOG_WARN, "cannot write %s/http.addr: %s", cfg.state_dir, err.message);
    fm_log(FM_LOG_INFO, "http: listening on %s:%u (viewer %s, token %s)", http_host, port,
           hcfg.viewer_dir[0] ? hcfg.viewer_dir : "built-in index",
           cfg.token[0] ? "required for writes" : "off");

    fm_modbus_server *modbus = NULL;
    if (strcmp(cfg.modbus_listen, "off") != 0) {
        fm_modbus_config mcfg;
        fm_modbus_config_default(&mcfg);
        unsigned mport;
        fm_daemon_split_addr(cfg.modbus_listen, mcfg.listen_addr, sizeof mcfg.listen_addr, &mport);
        mcfg.port = (uint16_t)mport;
        mcfg.enable_commands = cfg.modbus_commands;
        mcfg.enable_live = cfg.modbus_live;
        mcfg.watchdog_ms = cfg.modbus_watchdog_ms;
        mcfg.log = modbus_log;
        fm_modbus_service msvc;
        fm_jobs_modbus_service(jobs, &msvc);
        if (fm_modbus_server_start(&mcfg, &msvc, &modbus, &err) != FM_OK) {
            /* HTTP is the main face; a busy Modbus port must not keep the
             * daemon from serving jobs. */
            fm_log(FM_LOG_WARN, "modbus: not started: %s", err.message);
            modbus = NULL;
        } else {
            fm_log(FM_LOG_INFO, "modbus: listening on %s:%u", mcfg.listen_addr,
                   fm_modbus_server_port(modbus));
            /* Like http.addr: with port 0 this is how clients and tests
             * learn the port bound. */
            char maddr[128];
            int mn = snprintf(maddr, sizeof maddr, "%s:%u\n", mcfg.listen_addr,
                              fm_modbus_server_port(modbus));
            if (fm_store_write_atomic(cfg.state_dir, "modbus.addr", maddr, (size_t)mn, &err) !=
                FM_OK)
                fm_log(FM_LOG_WARN, "cannot write %s/modbus.addr: %s", cfg.state_dir, err.message);
        }
    }


    fm_redis_queue *queue = NULL;
    if (cfg.queue[0] && strcmp(cfg.queue, "off") != 0) {
        char consumer[300];
        if (cfg.queue_consumer[0]) {
            snprintf(consumer, sizeof consumer, "%s", cfg.queue_consumer);
        } else {
            char host[200] = "frepmilld";
            gethostname(host, sizeof host - 1);
            host[sizeof host - 1] = '\0';
            snprintf(consumer, sizeof consumer, "%s-%ld", host, (long)getpid());
        }
        fm_redis_queue_config qcfg = {.url = cfg.queue,
                                      .stream = cfg.queue_stream,
                                      .group = cfg.queue_group,
                                      .consumer = consumer,
                                      .claim_s = cfg.queue_claim_s,
                                      .max_job_bytes = hcfg.max_request_bytes,
                                      .capacity = cfg.workers};
        queue = fm_redis_queue_start(&qcfg, jobs, &err);
        if (!queue) {
            fm_log(FM_LOG_ERROR, "queue: %s", err.message);
            fm_http_server_stop(http);
            fm_mtconnect_stop(jobs, mtconnect);
            fm_modbus_server_stop(modbus);
            fm_jobs_close(jobs);
            return 2;
        }
        fm_log(FM_LOG_INFO, "queue: consuming %s as %s of group %s", cfg.queue_stream, consumer,
               cfg.queue_group);
    }

    fm_live_source *live_source = NULL;
    if (cfg.live_source[0]) {
        if (strcmp(cfg.live_units, "mm") != 0 && strcmp(cfg.live_units, "inch") != 0) {
            fm_log(FM_LOG_ERROR, "live_units must be mm or inch, not %s", cfg.live_units);
            fm_redis_queue_stop(queue);
            fm_jobs_begin_shutdown(jobs);
            fm_http_server_stop(http);
            fm_mtconnect_stop(jobs, mtconnect);
            fm_modbus_server_stop(modbus);
            fm_jobs_close(jobs);
            return 2;
        }
        fm_live_source_config lcfg = {.source = cfg.live_source,
                                      .map = cfg.live_map,
                                      .machine = cfg.live_machine,
                                      .scale = strcmp(cfg.live_units, "inch") ? 1.0 : 25.4,
                                      .reconnect_max_s = cfg.live_reconnect_max_s};
        if (fm_live_source_start(&lcfg, jobs, &live_source, &err) != FM_OK) {
            fm_log(FM_LOG_ERROR, "live_source: %s", err.message);
            fm_redis_queue_stop(queue);
            fm_jobs_begin_shutdown(jobs);
            fm_http_server_stop(http);
            fm_mtconnect_stop(jobs, mtconnect);
            fm_modbus_server_stop(modbus);
            fm_jobs_close(jobs);
            return 2;
        }
    }

    if (cfg.demo) submit_demo(jobs, &cfg, port);
    fm_log(FM_LOG_INFO, "frepmilld ready: %d workers, state in %s", cfg.workers, cfg.state_dir);

    for (;;) {
        int sig = sigwaitinfo(&signals, NULL);
        if (sig < 0) {
            if (errno == EINTR) continue;
            break;
        }
        if (sig == SIGHUP) {
            if (fm_log_reopen() != 0) fm_log(FM_LOG_WARN, "SIGHUP: cannot reopen the log file");
            fm_log(FM_LOG_INFO, "SIGHUP: log reopened");
            continue;
        }
        fm_log(FM_LOG_INFO, "%s: stopping", sig == SIGTERM ? "SIGTERM" : "SIGINT");
        break;
    }
    /* Order: no new requests, then jobs stop at their next cut and are
     * snapshotted for the next start. */
    fm_live_source_stop(live_source); /* gives no more positions */
    fm_redis_queue_stop(queue); /* takes no more; writes the results it holds */
    fm_jobs_begin_shutdown(jobs);
    fm_http_server_stop(http);
    fm_mtconnect_stop(jobs, mtconnect); /* after the server: its streams read the agent */
    fm_modbus_server_stop(modbus);
    fm_jobs_close(jobs);
    fm_log(FM_LOG_INFO, "frepmilld stopped");
    fm_log_close();
    return 0;
}
