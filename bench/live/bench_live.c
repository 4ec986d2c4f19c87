/* bench_live.c: the latency an HMI sees in live mode, through the real path.
 * For each row it starts frepmilld (live mode on Modbus, a private state
 * folder, free ports), follows the live job's server-sent events over a raw
 * HTTP socket, and writes positions with libmodbus as a controller would:
 * the tool placed at (10, Y), plunged DEPTH deep, then MOVES positions STEP
 * mm apart along X at that depth, one every INTERVAL ms as a 20 Hz HMI sends
 * them (or back to back: each write after the last one's event). For each
 * it measures the time from the Modbus write to the `chunks` event that
 * announces the move's meshes, and prints one table row per row: p50, p95,
 * max, the daemon's CPU per move, the load average and the ratios to issue
 * 37's goals (p50 <= 10 ms, p95 <= 20 ms on every row; goal 5 ms).
 *
 *   bench_live FREPMILLD [--row Y]... [--rows all] [--interval-ms MS |
 *              --back-to-back] [--voxel MM] [--moves N] [--step MM]
 *              [--depth MM] [--stock SPEC] [--feed MM_MIN]
 *              [--snapshots] [--log-level LEVEL] [--keep]
 * (--keep leaves each row's state folder and the daemon's log, for
 * --log-level debug's per-publication timings.) The daemon snapshots its
 * stock only every hour: the snapshot (0.3-0.6 s of the worker's time
 * every 10 s of work by default, docs/daemon.md) would fall among the moves
 * or not depending on how long the first meshes took, and stall the moves
 * behind it; --snapshots keeps the daemon's 10 s.
 *
 * Defaults: issue 37's rows (--rows all: y = 10, which crosses two chunk
 * seams, and y = 30), one write every 50 ms, 0.1 mm voxels, 60 moves of
 * 1 mm, 2 mm deep, a 6 mm flat end mill, stock box:0,0,-30,100,60,0. Not a
 * test: it prints figures and exits 0 unless something failed to run. */
#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <jansson.h>
#include <math.h>
#include <modbus.h>
#include <netinet/in.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "bench_clock.h"

#define SSE_BUF 65536

static double now_ms(void)
{
    return 1e3 * bench_wall_s();
}

static void sleep_ms(double ms)
{
    struct timespec ts = {(time_t)(ms / 1e3), (long)(fmod(ms, 1e3) * 1e6)};
    nanosleep(&ts, NULL);
}

static int die(const char *what)
{
    fprintf(stderr, "bench_live: %s\n", what);
    return 1;
}

/* ------------------------------------------------------------- daemon -- */

/* The start of a small file (a /proc record, an address file) into buf. */
static int read_file(const char *path, char *buf, size_t size)
{
    char *data;
    size_t n;
    if (fm_file_read(path, NULL, 1 << 20, &data, &n, NULL) != FM_OK) return -1;
    snprintf(buf, size, "%s", data);
    free(data);
    return (int)strlen(buf);
}

/* "http://127.0.0.1:PORT" or "127.0.0.1:PORT" -> port. */
static int port_of(const char *text)
{
    const char *colon = strrchr(text, ':');
    return colon ? atoi(colon + 1) : 0;
}

static double cpu_s(pid_t pid)
{
    char path[64], buf[4096];
    snprintf(path, sizeof path, "/proc/%d/stat", (int)pid);
    if (read_file(path, buf, sizeof buf) <= 0) return 0;
    const char *p = strrchr(buf, ')');
    if (!p) return 0;
    unsigned long utime = 0, stime = 0;
    /* fields after the command: state(3) ... utime(14) stime(15) */
    int field = 2;
    for (const char *q = p + 1; *q && field < 15; q++) {
        if (*q == ' ') {
            field++;
            if (field == 14) utime = strtoul(q + 1, NULL, 10);
            if (field == 15) stime = strtoul(q + 1, NULL, 10);
        }
    }
    return (double)(utime + stime) / (double)sysconf(_SC_CLK_TCK);
}

/* ----------------------------------------------------------------- http -- */

static int connect_local(int port)
{
    int fd = socket(AF_INET, SOCK_STREAM, 0);
    if (fd < 0) return -1;
    struct sockaddr_in a;
    memset(&a, 0, sizeof a);
    a.sin_family = AF_INET;
    a.sin_port = htons((unsigned short)port);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (connect(fd, (struct sockaddr *)&a, sizeof a) != 0) {
        close(fd);
        return -1;
    }
    return fd;
}

/* GET path (HTTP/1.0: the server closes after the answer); the body, or NULL. */
static char *http_get(int port, const char *path)
{
    int fd = connect_local(port);
    if (fd < 0) return NULL;
    char req[512];
    int n = snprintf(req, sizeof req, "GET %s HTTP/1.0\r\nHost: 127.0.0.1\r\n\r\n", path);
    if (write(fd, req, (size_t)n) != n) {
        close(fd);
        return NULL;
    }
    size_t cap = 65536, len = 0;
    char *buf = malloc(cap);
    for (ssize_t r; buf && (r = read(fd, buf + len, cap - len - 1)) > 0;) {
        len += (size_t)r;
        if (len + 1 == cap) {
            char *b = realloc(buf, cap * 2);
            if (!b) {
                free(buf);
                buf = NULL;
                break;
            }
            buf = b;
            cap *= 2;
        }
    }
    close(fd);
    if (!buf) return NULL;
    buf[len] = '\0';
    char *body = strstr(buf, "\r\n\r\n");
    if (!body) {
        free(buf);
        return NULL;
    }
    memmove(buf, body + 4, strlen(body + 4) + 1);
    return buf;
}

/* The server-sent event stream of one job. */
typedef struct sse {
    int fd;
    char buf[SSE_BUF];
    size_t len;
    char type[32];
} sse;

static int sse_open(sse *s, int port, const char *id)
{
    memset(s, 0, sizeof *s);
    s->fd = connect_local(port);
    if (s->fd < 0) return -1;
    char req[256];
    int n = snprintf(req, sizeof req,
                     "GET /v1/jobs/%s/events HTTP/1.1\r\nHost: 127.0.0.1\r\nAccept: "
                     "text/event-stream\r\n\r\n",
                     id);
    return write(s->fd, req, (size_t)n) == n ? 0 : -1;
}

/* The next `chunks` event's version and program time, waiting until the
 * monotonic time until_ms; -1 when none came by then. */
static long long sse_next_chunks(sse *s, double until_ms, double *program_time_s)
{
    for (;;) {
        char *nl;
        while ((nl = memchr(s->buf, '\n', s->len))) {
            *nl = '\0';
            long long version = -1;
            if (!strncmp(s->buf, "event: ", 7)) {
                snprintf(s->type, sizeof s->type, "%s", s->buf + 7);
            } else if (!strncmp(s->buf, "data: ", 6) && !strcmp(s->type, "chunks")) {
                const char *v = strstr(s->buf, "\"version\":");
                const char *t = strstr(s->buf, "\"program_time_s\":");
                if (v) version = strtoll(v + 10, NULL, 10);
                if (t && program_time_s) *program_time_s = strtod(t + 17, NULL);
            }
            size_t used = (size_t)(nl - s->buf) + 1;
            memmove(s->buf, nl + 1, s->len - used);
            s->len -= used;
            if (version >= 0) return version;
        }
        double left = until_ms - now_ms();
        if (left <= 0) return -1;
        struct pollfd p = {s->fd, POLLIN, 0};
        if (poll(&p, 1, (int)ceil(left)) <= 0) return -1;
        ssize_t r = read(s->fd, s->buf + s->len, sizeof s->buf - s->len - 1);
        if (r <= 0) return -1;
        s->len += (size_t)r;
    }
}

/* --------------------------------------------------------------- modbus -- */

/* A float32 in two registers, high word first (the daemon's default ABCD
 * order; libmodbus's own helpers swap bytes differently across versions). */
static void pack_float(double v, uint16_t out[2])
{
    float f = (float)v;
    uint32_t bits;
    memcpy(&bits, &f, sizeof bits);
    out[0] = (uint16_t)(bits >> 16);
    out[1] = (uint16_t)(bits & 0xffffu);
}

static int write_position(modbus_t *mb, double x, double y, double z, int tool)
{
    uint16_t regs[7];
    pack_float(x, regs);
    pack_float(y, regs + 2);
    pack_float(z, regs + 4);
    regs[6] = (uint16_t)tool;
    return modbus_write_registers(mb, 110, 7, regs) == 7 ? 0 : -1;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double percentile(const double *sorted, int n, double q)
{
    double pos = q * (n - 1);
    int i = (int)floor(pos);
    if (i >= n - 1) return sorted[n - 1];
    return sorted[i] + (sorted[i + 1] - sorted[i]) * (pos - i);
}

/* What every row shares: the daemon, the stock, the moves and their pace. */
typedef struct bench_opts {
    const char *daemon, *stock, *log_level;
    double voxel, step, depth, feed;
    double interval_ms; /* between two writes; 0: each write waits for the last one's event */
    int moves, keep;
    int snapshots; /* keep the daemon's snapshot_interval_s (10 s of work) */
} bench_opts;

/* One row's figures. */
typedef struct row_result {
    double y;
    int done;
    double p50, p95, max, mean, min;
    double cpu_ms_per_move;
    double load[3];
} row_result;

/* One row: a daemon of its own (a fresh stock, the same first snapshot
 * timing for every row), the tool placed at (10, y) and plunged to -depth,
 * then the moves along X at y. Each move's latency runs from its Modbus
 * write to the first `chunks` event whose program time covers it: live
 * moves are feed moves of step mm, so move i (from 1) is cut once the
 * published program time reaches the plunge's plus i * step / feed. That
 * holds when the writes come faster than the meshes (a paced HMI does not
 * wait for them): one publication then answers several moves. */
static int run_row(const bench_opts *o, double y, row_result *res)
{
    memset(res, 0, sizeof *res);
    res->y = y;
    char dir[] = "/tmp/bench-live-XXXXXX";
    if (!mkdtemp(dir)) return die("mkdtemp failed");
    char path[1300], state[1200], tools[1200], log[1200];
    snprintf(state, sizeof state, "%s/state", dir);
    snprintf(tools, sizeof tools, "%s/tools.json", dir);
    snprintf(log, sizeof log, "%s/daemon.log", dir);
    FILE *f = fopen(tools, "w");
    if (!f) return die("cannot write the tool table");
    fprintf(f, "{\"units\": \"mm\", \"tools\": [{\"number\": 1, \"shape\": \"flat\", \"diameter\": 6, "
               "\"flute_length\": 20, \"length\": 40, \"center_cutting\": true}]}\n");
    fclose(f);

    char voxel_text[32], feed_text[32];
    snprintf(voxel_text, sizeof voxel_text, "%g", o->voxel);
    snprintf(feed_text, sizeof feed_text, "%g", o->feed);
    pid_t pid = fork();
    if (pid < 0) return die("fork failed");
    if (pid == 0) {
        int fd = open(log, O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (fd >= 0) {
            dup2(fd, 1);
            dup2(fd, 2);
        }
        execl(o->daemon, o->daemon, "--listen", "127.0.0.1:0", "--modbus-listen", "127.0.0.1:0",
              "--state-dir", state, "--modbus-live", "yes", "--live-stock", o->stock,
              "--live-tools", tools, "--live-voxel", voxel_text, "--live-feed", feed_text,
              "--workers", "1", "--log-level", o->log_level, "--snapshot-interval-s",
              o->snapshots ? "10" : "3600", (char *)NULL);
        _exit(127);
    }
    int http_port = 0, modbus_port = 0;
    char text[256];
    for (double t0 = now_ms(); now_ms() - t0 < 30000 && !modbus_port;) {
        snprintf(path, sizeof path, "%s/http.addr", state);
        if (!http_port && read_file(path, text, sizeof text) > 0) http_port = port_of(text);
        snprintf(path, sizeof path, "%s/modbus.addr", state);
        if (read_file(path, text, sizeof text) > 0) modbus_port = port_of(text);
        sleep_ms(20);
    }
    const int moves = o->moves;
    int status = 1;
    modbus_t *mb = NULL;
    sse events = {.fd = -1};
    double *lat = calloc((size_t)moves, sizeof *lat);
    double *written = calloc((size_t)moves, sizeof *written);
    if (!http_port || !modbus_port || !lat || !written) {
        die("the daemon did not start (see its log)");
        goto out;
    }
    mb = modbus_new_tcp("127.0.0.1", modbus_port);
    if (!mb || modbus_connect(mb) != 0) {
        die("cannot connect to the Modbus server");
        goto out;
    }
    modbus_set_response_timeout(mb, 5, 0);
    if (modbus_write_register(mb, 117, 1) != 1) {
        die("cannot switch live mode on");
        goto out;
    }
    /* The live job is the newest job. */
    char id[64] = "";
    for (double t0 = now_ms(); !id[0] && now_ms() - t0 < 10000; sleep_ms(20)) {
        char *body = http_get(http_port, "/v1/jobs");
        json_error_t jerr;
        json_t *list = body ? json_loads(body, 0, &jerr) : NULL;
        free(body);
        json_t *jobs = json_object_get(list, "jobs");
        size_t n = json_array_size(jobs);
        const char *last = n ? json_string_value(json_object_get(json_array_get(jobs, n - 1), "id"))
                             : NULL;
        if (last) snprintf(id, sizeof id, "%s", last);
        json_decref(list);
    }
    if (!id[0] || sse_open(&events, http_port, id) != 0) {
        die("no live job or no event stream");
        goto out;
    }

    /* Place the tool, plunge (warm-up: the first meshes), then the moves. */
    const double x0 = 10, z = -o->depth;
    double plunged_s = 0, pt = 0;
    write_position(mb, x0, y, 5, 1);
    write_position(mb, x0, y, z, 1);
    /* The first meshes (the whole stock) and the plunge's (its program
     * time: 5 + depth mm at the feed), then quiet for 1 s: nothing is
     * pending. The chunk list answers once the last publication's Draco
     * bytes exist (a live job announces its meshes before it encodes them),
     * and the publication after it waits for them too: quiet for 1 s once
     * more after the list. */
    const double plunge_s = (5 + o->depth) / o->feed * 60.0;
    double until = now_ms() + 120000;
    while (sse_next_chunks(&events, until, &pt) >= 0)
        if ((plunged_s = pt) >= plunge_s - 1e-6) until = now_ms() + 1000;
    if (plunged_s < plunge_s - 1e-6) {
        die("the plunge's meshes were not announced within 120 s");
        goto out;
    }
    snprintf(path, sizeof path, "/v1/jobs/%s/chunks?since=0", id);
    free(http_get(http_port, path));
    while (sse_next_chunks(&events, now_ms() + 1000, &pt) >= 0) plunged_s = pt;
    const double move_s = o->step / o->feed * 60.0;
    double cpu0 = cpu_s(pid);
    double wall0 = now_ms();
    int sent = 0, answered = 0;
    while (answered < moves) {
        /* The next write is due on the HMI's clock, or (back to back) once
         * every write so far is answered. */
        double due = sent >= moves           ? now_ms() + 60000
                     : o->interval_ms > 0    ? wall0 + o->interval_ms * sent
                     : answered == sent      ? now_ms()
                                             : now_ms() + 60000;
        if (sent < moves && now_ms() >= due) {
            written[sent] = now_ms();
            if (write_position(mb, x0 + o->step * (sent + 1), y, z, 1) != 0) {
                die("a Modbus write failed");
                break;
            }
            sent++;
            continue;
        }
        if (sse_next_chunks(&events, due, &pt) < 0) {
            if (sent >= moves || (o->interval_ms <= 0 && answered < sent)) {
                fprintf(stderr, "bench_live: row y=%g: move %d: no chunks event within 60 s\n", y,
                        answered + 1);
                break;
            }
            continue; /* the next write is due */
        }
        const double t = now_ms();
        while (answered < sent && pt >= plunged_s + move_s * (answered + 1) - 1e-6) {
            lat[answered] = t - written[answered];
            answered++;
        }
    }
    double cpu = cpu_s(pid) - cpu0;
    modbus_write_register(mb, 117, 0);
    const int done = answered;
    if (done < 2) goto out;
    double mean = 0;
    for (int i = 0; i < done; i++) mean += lat[i];
    mean /= done;
    qsort(lat, (size_t)done, sizeof *lat, cmp_double);
    res->done = done;
    res->p50 = percentile(lat, done, 0.5);
    res->p95 = percentile(lat, done, 0.95);
    res->max = lat[done - 1];
    res->min = lat[0];
    res->mean = mean;
    res->cpu_ms_per_move = cpu * 1e3 / done;
    if (read_file("/proc/loadavg", text, sizeof text) > 0)
        sscanf(text, "%lf %lf %lf", &res->load[0], &res->load[1], &res->load[2]);
    status = 0;
out:
    free(lat);
    free(written);
    if (events.fd >= 0) close(events.fd);
    if (mb) {
        modbus_close(mb);
        modbus_free(mb);
    }
    kill(pid, SIGTERM);
    int ws;
    waitpid(pid, &ws, 0);
    if (status || o->keep) fprintf(stderr, "bench_live: row y=%g: daemon log kept in %s\n", y, log);
    if (!o->keep && !status) {
        char cmd[1300];
        snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
        if (system(cmd) != 0) fprintf(stderr, "bench_live: cannot remove %s\n", dir);
    }
    return status;
}

/* issue 37's rows: y = 10 crosses two chunk seams, y = 30 none */
static const double issue_rows[] = {10, 30};
#define MAX_ROWS 16
/* issue 37's goals */
#define GOAL_P50_MS 10.0
#define GOAL_P95_MS 20.0
#define GOAL_MS 5.0

int main(int argc, char **argv)
{
    if (argc < 2)
        return die("usage: bench_live FREPMILLD [--row Y]... [--rows all] [--interval-ms MS | "
                   "--back-to-back] [--voxel MM] [--moves N] [--step MM] [--depth MM] "
                   "[--stock SPEC] [--feed MM_MIN] [--snapshots] [--log-level LEVEL] [--keep]");
    bench_opts o = {argv[1], "box:0,0,-30,100,60,0", "warn", 0.1, 1.0, 2.0, 1000, 50, 60, 0, 0};
    double rows[MAX_ROWS];
    int nrows = 0;
    for (int i = 2; i < argc; i++) {
        const char *v = i + 1 < argc ? argv[i + 1] : "";
        if (!strcmp(argv[i], "--voxel")) o.voxel = atof(v), i++;
        else if (!strcmp(argv[i], "--moves")) o.moves = atoi(v), i++;
        else if (!strcmp(argv[i], "--step")) o.step = atof(v), i++;
        else if (!strcmp(argv[i], "--depth")) o.depth = atof(v), i++;
        else if (!strcmp(argv[i], "--stock")) o.stock = v, i++;
        else if (!strcmp(argv[i], "--feed")) o.feed = atof(v), i++;
        else if (!strcmp(argv[i], "--interval-ms")) o.interval_ms = atof(v), i++;
        else if (!strcmp(argv[i], "--back-to-back")) o.interval_ms = 0;
        else if (!strcmp(argv[i], "--keep")) o.keep = 1;
        else if (!strcmp(argv[i], "--snapshots")) o.snapshots = 1;
        else if (!strcmp(argv[i], "--log-level")) o.log_level = v, i++;
        else if (!strcmp(argv[i], "--rows") && !strcmp(v, "all")) nrows = 0, i++;
        else if (!strcmp(argv[i], "--row") && nrows < MAX_ROWS && *v) rows[nrows++] = atof(v), i++;
        else return die("unknown option");
    }
    if (!(o.voxel > 0) || o.moves < 2 || o.moves > 100000 || !(o.step > 0) || !(o.feed > 0) ||
        !(o.interval_ms >= 0))
        return die("bad option value");
    if (!nrows)
        for (size_t i = 0; i < sizeof issue_rows / sizeof issue_rows[0]; i++)
            rows[nrows++] = issue_rows[i];

    char pace[64];
    if (o.interval_ms > 0)
        snprintf(pace, sizeof pace, "one every %g ms (%.3g Hz)", o.interval_ms, 1e3 / o.interval_ms);
    else
        snprintf(pace, sizeof pace, "back to back");
    printf("bench_live: %d moves of %g mm along X at %g mm deep, %s; voxel %g mm, stock %s, "
           "6 mm flat, feed %g mm/min; %ld cores\n",
           o.moves, o.step, o.depth, pace, o.voxel, o.stock, o.feed, sysconf(_SC_NPROCESSORS_ONLN));
    printf("  write -> chunks event (ms)\n");
    printf("  %-6s %5s %7s %7s %7s %7s %7s %11s %8s %8s %8s %s\n", "row y", "moves", "p50", "p95",
           "max", "mean", "min", "CPU/move", "p50/10", "p95/20", "p50/5", "load");
    int failed = 0;
    for (int r = 0; r < nrows; r++) {
        row_result res;
        if (run_row(&o, rows[r], &res) != 0) {
            failed = 1;
            printf("  %-6g (failed: see above)\n", rows[r]);
            continue;
        }
        printf("  %-6g %5d %7.1f %7.1f %7.1f %7.1f %7.1f %8.1f ms %8.2f %8.2f %8.2f %.2f %.2f "
               "%.2f\n",
               res.y, res.done, res.p50, res.p95, res.max, res.mean, res.min, res.cpu_ms_per_move,
               res.p50 / GOAL_P50_MS, res.p95 / GOAL_P95_MS, res.p50 / GOAL_MS, res.load[0],
               res.load[1], res.load[2]);
        fflush(stdout);
    }
    printf("  goals (issue 37): p50 <= %g ms and p95 <= %g ms on every row; goal %g ms. CPU/move: "
           "the daemon's CPU over the moves.\n",
           GOAL_P50_MS, GOAL_P95_MS, GOAL_MS);
    return failed;
}
