/* bench_live.c: the latency an HMI sees in live mode, through the real path.
 * It starts frepmilld (live mode on Modbus, a private state folder, free
 * ports), follows the live job's server-sent events over HTTP, and writes
 * positions with libmodbus as a controller would: after a plunge, MOVES
 * positions STEP mm apart along X at the cutting depth, one at a time. For
 * each it measures the time from the Modbus write to the `chunks` event that
 * announces the changed meshes (their version above any seen before the
 * write), and prints p50, p95, max, the daemon's CPU time over the moves and
 * the load average, and the ratios to the bounds (issue 18: p50 <= 20 ms,
 * p95 <= 50 ms; goal 5 ms).
 *
 *   bench_live FREPMILLD [--voxel MM] [--moves N] [--step MM] [--depth MM]
 *              [--stock SPEC] [--log-level LEVEL] [--keep]
 * (--keep leaves the state folder and the daemon's log, for --log-level
 * debug's per-publication timings.)
 *
 * Defaults: 0.1 mm voxels, 60 moves of 1 mm, 1 mm deep, a 6 mm flat end mill,
 * stock box:0,0,-10,100,60,0. Not a test: it prints figures and exits 0
 * unless something failed to run. */
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

/* The next `chunks` event's version, waiting up to timeout_ms; -1 on timeout. */
static long long sse_next_chunks(sse *s, double timeout_ms)
{
    double until = now_ms() + timeout_ms;
    for (;;) {
        char *nl;
        while ((nl = memchr(s->buf, '\n', s->len))) {
            *nl = '\0';
            long long version = -1;
            if (!strncmp(s->buf, "event: ", 7)) {
                snprintf(s->type, sizeof s->type, "%s", s->buf + 7);
            } else if (!strncmp(s->buf, "data: ", 6) && !strcmp(s->type, "chunks")) {
                const char *v = strstr(s->buf, "\"version\":");
                if (v) version = strtoll(v + 10, NULL, 10);
            }
            size_t used = (size_t)(nl - s->buf) + 1;
            memmove(s->buf, nl + 1, s->len - used);
            s->len -= used;
            if (version >= 0) return version;
        }
        double left = until - now_ms();
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

int main(int argc, char **argv)
{
    if (argc < 2) return die("usage: bench_live FREPMILLD [--voxel MM] [--moves N] [--step MM] "
                             "[--depth MM] [--stock SPEC] [--keep]");
    const char *daemon = argv[1], *stock = "box:0,0,-10,100,60,0";
    double voxel = 0.1, step = 1.0, depth = 1.0;
    int moves = 60, keep = 0;
    const char *log_level = "warn";
    for (int i = 2; i < argc; i++) {
        const char *v = i + 1 < argc ? argv[i + 1] : "";
        if (!strcmp(argv[i], "--voxel")) voxel = atof(v), i++;
        else if (!strcmp(argv[i], "--moves")) moves = atoi(v), i++;
        else if (!strcmp(argv[i], "--step")) step = atof(v), i++;
        else if (!strcmp(argv[i], "--depth")) depth = atof(v), i++;
        else if (!strcmp(argv[i], "--stock")) stock = v, i++;
        else if (!strcmp(argv[i], "--keep")) keep = 1;
        else if (!strcmp(argv[i], "--log-level")) log_level = v, i++;
        else return die("unknown option");
    }
    if (!(voxel > 0) || moves < 2 || moves > 100000 || !(step > 0)) return die("bad option value");

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

    char voxel_text[32];
    snprintf(voxel_text, sizeof voxel_text, "%g", voxel);
    pid_t pid = fork();
    if (pid < 0) return die("fork failed");
    if (pid == 0) {
        int fd = open(log, O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (fd >= 0) {
            dup2(fd, 1);
            dup2(fd, 2);
        }
        execl(daemon, daemon, "--listen", "127.0.0.1:0", "--modbus-listen", "127.0.0.1:0",
              "--state-dir", state, "--modbus-live", "yes", "--live-stock", stock,
              "--live-tools", tools, "--live-voxel", voxel_text, "--workers", "1",
              "--log-level", log_level, (char *)NULL);
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
    int status = 1;
    modbus_t *mb = NULL;
    sse events = {.fd = -1};
    double *lat = calloc((size_t)moves, sizeof *lat);
    if (!http_port || !modbus_port || !lat) {
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
    const double x0 = 10, y = 30, z = -depth;
    long long seen = -1, v;
    write_position(mb, x0, y, 5, 1);
    write_position(mb, x0, y, z, 1);
    /* The first meshes (the whole stock) and the plunge's, then quiet for
     * 1 s: nothing is pending. */
    for (double wait = 120000; (v = sse_next_chunks(&events, wait)) >= 0; wait = 1000)
        if (v > seen) seen = v;
    double cpu0 = cpu_s(pid);
    double wall0 = now_ms();
    int done = 0;
    for (int i = 0; i < moves; i++) {
        double t0 = now_ms();
        if (write_position(mb, x0 + step * (i + 1), y, z, 1) != 0) {
            die("a Modbus write failed");
            break;
        }
        for (;;) {
            v = sse_next_chunks(&events, 60000);
            if (v < 0 || v > seen) break;
        }
        if (v < 0) {
            fprintf(stderr, "bench_live: move %d: no chunks event within 60 s\n", i + 1);
            break;
        }
        seen = v;
        lat[done++] = now_ms() - t0;
    }
    double cpu = cpu_s(pid) - cpu0, wall = now_ms() - wall0;
    modbus_write_register(mb, 117, 0);
    if (done < 2) goto out;
    double mean = 0;
    for (int i = 0; i < done; i++) mean += lat[i];
    mean /= done;
    qsort(lat, (size_t)done, sizeof *lat, cmp_double);
    double p50 = percentile(lat, done, 0.5), p95 = percentile(lat, done, 0.95);
    double load[3] = {0, 0, 0};
    if (read_file("/proc/loadavg", text, sizeof text) > 0)
        sscanf(text, "%lf %lf %lf", &load[0], &load[1], &load[2]);
    printf("bench_live: %d moves of %g mm at %g mm deep, voxel %g mm, stock %s, 6 mm flat\n", done,
           step, depth, voxel, stock);
    printf("  write -> chunks event: p50 %.1f ms, p95 %.1f ms, max %.1f ms, mean %.1f ms, min %.1f "
           "ms\n",
           p50, p95, lat[done - 1], mean, lat[0]);
    printf("  daemon CPU %.2f s over %.2f s wall (%.1f ms CPU per move); load average %.2f %.2f "
           "%.2f on %ld cores\n",
           cpu, wall / 1e3, cpu * 1e3 / done, load[0], load[1], load[2],
           sysconf(_SC_NPROCESSORS_ONLN));
    printf("  ratios: p50 / 20 ms bound %.2f, p95 / 50 ms bound %.2f, p50 / 5 ms goal %.2f\n",
           p50 / 20, p95 / 50, p50 / 5);
    status = 0;
out:
    free(lat);
    if (events.fd >= 0) close(events.fd);
    if (mb) {
        modbus_close(mb);
        modbus_free(mb);
    }
    kill(pid, SIGTERM);
    int ws;
    waitpid(pid, &ws, 0);
    if (status && !keep) fprintf(stderr, "bench_live: daemon log kept in %s\n", log);
    if (!keep && !status) {
        char cmd[1300];
        snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
        if (system(cmd) != 0) fprintf(stderr, "bench_live: cannot remove %s\n", dir);
    }
    return status;
}
