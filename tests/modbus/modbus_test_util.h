/* modbus_test_util.h: what the Modbus tests share: a fake daemon service that
 * records every call, loopback socket helpers with deadlines, the attack-frame
 * file reader, and running an outside program (mbpoll, node) with a time
 * limit. Header-only so each test stays one program. */
#ifndef FM_MODBUS_TEST_UTIL_H
#define FM_MODBUS_TEST_UTIL_H

#include <arpa/inet.h>
#include <ctype.h>
#include <errno.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "protocols/modbus/modbus_server.h"

static inline int64_t mt_now_ms(void) { return (int64_t)(fm_clock_monotonic_s() * 1000); }

static inline void mt_sleep_ms(int ms)
{
    struct timespec ts = {ms / 1000, (long)(ms % 1000) * 1000000L};
    while (nanosleep(&ts, &ts) != 0 && errno == EINTR) {
    }
}

/* ---- the fake service ------------------------------------------------- */

#define MT_MAX_CALLS 256

typedef struct mt_call {
    int kind; /* 'c' command, 'p' position, 'm' live mode, 'w' watchdog */
    int command;
    uint32_t argument;
    double xyz[3];
    int tool;
} mt_call;

typedef struct mt_service {
    pthread_mutex_t lock;
    fm_modbus_status status;  /* returned by read_status */
    int64_t block_start_ms;   /* when > 0, block = status.block + elapsed/block_period_ms */
    int block_period_ms;
    const char *command_refusal; /* NULL: command() accepts; else the reason it refuses with */
    int read_count;
    mt_call calls[MT_MAX_CALLS];
    int ncalls;
} mt_service;

static inline void mt_record(mt_service *m, mt_call c)
{
    pthread_mutex_lock(&m->lock);
    if (m->ncalls < MT_MAX_CALLS)
        m->calls[m->ncalls++] = c;
    pthread_mutex_unlock(&m->lock);
}

static void mt_read_status(void *ctx, fm_modbus_status *out)
{
    mt_service *m = ctx;
    pthread_mutex_lock(&m->lock);
    *out = m->status;
    if (m->block_start_ms > 0 && m->block_period_ms > 0)
        out->block += (uint32_t)((mt_now_ms() - m->block_start_ms) / m->block_period_ms);
    m->read_count++;
    pthread_mutex_unlock(&m->lock);
}

static fm_status mt_command(void *ctx, int command, uint32_t argument, fm_error *err)
{
    mt_service *m = ctx;
    mt_call c = {'c', command, argument, {0, 0, 0}, 0};
    mt_record(m, c);
    pthread_mutex_lock(&m->lock);
    const char *refusal = m->command_refusal;
    pthread_mutex_unlock(&m->lock);
    if (refusal) return fm_error_set_reason(err, FM_ERR_INPUT, refusal, "refused by the test");
    return FM_OK;
}

static fm_status mt_live_position(void *ctx, const double xyz[3], int tool, fm_error *err)
{
    (void)err;
    mt_call c = {'p', 0, 0, {xyz[0], xyz[1], xyz[2]}, tool};
    mt_record(ctx, c);
    return FM_OK;
}

static fm_status mt_live_mode(void *ctx, int on, fm_error *err)
{
    (void)err;
    mt_call c = {'m', on, 0, {0, 0, 0}, 0};
    mt_record(ctx, c);
    return FM_OK;
}

static void mt_watchdog(void *ctx)
{
    mt_call c = {'w', 0, 0, {0, 0, 0}, 0};
    mt_record(ctx, c);
}

/* A status with a value in every field, all exactly representable in float. */
static inline void mt_service_init(mt_service *m)
{
    memset(m, 0, sizeof *m);
    pthread_mutex_init(&m->lock, NULL);
    m->status.bits = FM_MODBUS_BIT_JOB_LOADED | FM_MODBUS_BIT_RUNNING | FM_MODBUS_BIT_COLLISION;
    m->status.block = 123456;        /* 0x0001E240 */
    m->status.source_line = 70000;   /* 0x00011170 */
    m->status.progress_permille = 417;
    m->status.tool = 7;
    m->status.tool_tip[0] = 12.5;
    m->status.tool_tip[1] = -3.25;
    m->status.tool_tip[2] = 100.125;
    m->status.program_time_s = 42.75;
    m->status.removed_mm3 = 1234.5;
    m->status.remaining_mm3 = 98765.25;
    m->status.removal_rate_mm3_s = 0.15625;
    m->status.finding_count = 3;
    m->status.first_finding_line = 65537; /* 0x00010001 */
    m->status.last_error = 0;
    m->status.selected_slot = 2;
}

static inline void mt_service_destroy(mt_service *m)
{
    pthread_mutex_destroy(&m->lock);
}

static inline fm_modbus_service mt_service_iface(mt_service *m)
{
    fm_modbus_service s = {m, mt_read_status, mt_command, mt_live_position, mt_live_mode, mt_watchdog};
    return s;
}

static inline int mt_count_calls(mt_service *m, int kind)
{
    pthread_mutex_lock(&m->lock);
    int n = 0;
    for (int i = 0; i < m->ncalls; i++)
        n += m->calls[i].kind == kind;
    pthread_mutex_unlock(&m->lock);
    return n;
}

/* ---- loopback sockets ---------------------------------------------------- */

static inline int mt_connect(uint16_t port)
{
    int fd = socket(AF_INET, SOCK_STREAM, 0);
    if (fd < 0)
        return -1;
    struct sockaddr_in a;
    memset(&a, 0, sizeof a);
    a.sin_family = AF_INET;
    a.sin_port = htons(port);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (connect(fd, (struct sockaddr *)&a, sizeof a) < 0) {
        close(fd);
        return -1;
    }
    int one = 1;
    setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    return fd;
}

static inline int mt_send_all(int fd, const uint8_t *buf, size_t len)
{
    size_t off = 0;
    while (off < len) {
        ssize_t n = send(fd, buf + off, len - off, MSG_NOSIGNAL);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0)
            return -1;
        off += (size_t)n;
    }
    return 0;
}

/* Read exactly len bytes within timeout_ms. Returns len, 0 on orderly close
 * or reset, -1 on timeout. */
static inline int mt_recv_exact(int fd, uint8_t *buf, size_t len, int timeout_ms)
{
    size_t got = 0;
    int64_t deadline = mt_now_ms() + timeout_ms;
    while (got < len) {
        int left = (int)(deadline - mt_now_ms());
        if (left <= 0)
            return -1;
        struct pollfd p = {fd, POLLIN, 0};
        int r = poll(&p, 1, left);
        if (r < 0 && errno == EINTR)
            continue;
        if (r <= 0)
            return -1;
        ssize_t n = recv(fd, buf + got, len - got, 0);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0)
            return 0;
        got += (size_t)n;
    }
    return (int)len;
}

/* Read one Modbus/TCP reply ADU. Returns its length, 0 closed, -1 timeout or
 * malformed. */
static inline int mt_recv_adu(int fd, uint8_t buf[260], int timeout_ms)
{
    int r = mt_recv_exact(fd, buf, 6, timeout_ms);
    if (r <= 0)
        return r;
    unsigned len = ((unsigned)buf[4] << 8) | buf[5];
    if (len < 2 || len > 254)
        return -1;
    r = mt_recv_exact(fd, buf + 6, len, timeout_ms);
    return r <= 0 ? (r == 0 ? 0 : -1) : (int)(6 + len);
}

/* Wait until the peer closes (1), or timeout (0). Discards any data. */
static inline int mt_wait_closed(int fd, int timeout_ms)
{
    int64_t deadline = mt_now_ms() + timeout_ms;
    uint8_t buf[512];
    for (;;) {
        int left = (int)(deadline - mt_now_ms());
        if (left <= 0)
            return 0;
        struct pollfd p = {fd, POLLIN, 0};
        int r = poll(&p, 1, left);
        if (r <= 0)
            continue;
        ssize_t n = recv(fd, buf, sizeof buf, 0);
        if (n <= 0)
            return 1;
    }
}

/* Build a request ADU: MBAP with transaction tid, unit 1, then the PDU. */
static inline size_t mt_adu(uint8_t *out, unsigned tid, const uint8_t *pdu, size_t pdu_len)
{
    out[0] = (uint8_t)(tid >> 8);
    out[1] = (uint8_t)tid;
    out[2] = 0;
    out[3] = 0;
    out[4] = (uint8_t)((pdu_len + 1) >> 8);
    out[5] = (uint8_t)(pdu_len + 1);
    out[6] = 1;
    memcpy(out + 7, pdu, pdu_len);
    return 7 + pdu_len;
}

/* ---- attack frame files -------------------------------------------------- */

enum { MT_EXPECT_EXCEPTION, MT_EXPECT_CLOSE, MT_EXPECT_INCOMPLETE };

typedef struct mt_attack {
    char name[128];
    uint8_t bytes[1024];
    size_t len;
    int expect;
    int code; /* for MT_EXPECT_EXCEPTION */
} mt_attack;

/* "# expect: exception 03" / "# expect: close" / "# expect: incomplete";
 * other '#' lines are comments; the rest is hex bytes. Returns 0 on success. */
static inline int mt_attack_load(const char *path, const char *name, mt_attack *a)
{
    FILE *f = fopen(path, "r");
    if (!f)
        return -1;
    memset(a, 0, sizeof *a);
    snprintf(a->name, sizeof a->name, "%.*s", (int)sizeof a->name - 1, name); /* names are short; longer ones are cut */
    a->expect = -1;
    char line[512];
    int bad = 0;
    while (fgets(line, sizeof line, f)) {
        if (line[0] == '#') {
            const char *e = strstr(line, "expect:");
            if (e) {
                e += 7;
                while (*e == ' ')
                    e++;
                if (strncmp(e, "exception", 9) == 0) {
                    a->expect = MT_EXPECT_EXCEPTION;
                    a->code = (int)strtol(e + 9, NULL, 16);
                } else if (strncmp(e, "close", 5) == 0) {
                    a->expect = MT_EXPECT_CLOSE;
                } else if (strncmp(e, "incomplete", 10) == 0) {
                    a->expect = MT_EXPECT_INCOMPLETE;
                }
            }
            continue;
        }
        for (char *p = line; *p;) {
            if (isspace((unsigned char)*p)) {
                p++;
                continue;
            }
            char *end;
            long v = strtol(p, &end, 16);
            if (end == p || v < 0 || v > 255 || a->len >= sizeof a->bytes) {
                bad = 1;
                break;
            }
            a->bytes[a->len++] = (uint8_t)v;
            p = end;
        }
    }
    fclose(f);
    return bad || a->expect < 0 || a->len == 0 ? -1 : 0;
}

/* ---- outside programs ---------------------------------------------------- */

/* Is an executable called name on PATH? */
static inline int mt_have_program(const char *name)
{
    const char *path = getenv("PATH");
    if (!path)
        return 0;
    char dir[4096];
    while (*path) {
        size_t n = strcspn(path, ":");
        if (n > 0 && n < sizeof dir - 64 - strlen(name)) {
            memcpy(dir, path, n);
            snprintf(dir + n, sizeof dir - n, "/%s", name);
            if (access(dir, X_OK) == 0)
                return 1;
        }
        path += n;
        if (*path == ':')
            path++;
    }
    return 0;
}

/* Run argv (argv[0] looked up on PATH) in dir (NULL = here), capture stdout
 * (stderr passes through) into out, kill it after timeout_ms. Returns the
 * exit status, or -1 when it could not run, was killed or timed out. */
static inline int mt_run(char *const argv[], const char *dir, char *out, size_t out_size, int timeout_ms)
{
    int p[2];
    if (pipe(p) < 0)
        return -1;
    pid_t pid = fork();
    if (pid < 0) {
        close(p[0]);
        close(p[1]);
        return -1;
    }
    if (pid == 0) {
        dup2(p[1], 1);
        close(p[0]);
        close(p[1]);
        if (dir && chdir(dir) != 0)
            _exit(126);
        execvp(argv[0], argv);
        _exit(127);
    }
    close(p[1]);
    size_t got = 0;
    int64_t deadline = mt_now_ms() + timeout_ms;
    int timed_out = 0;
    for (;;) {
        int left = (int)(deadline - mt_now_ms());
        if (left <= 0) {
            timed_out = 1;
            break;
        }
        struct pollfd pf = {p[0], POLLIN, 0};
        int r = poll(&pf, 1, left);
        if (r < 0 && errno == EINTR)
            continue;
        if (r <= 0)
            continue;
        char tmp[4096];
        ssize_t n = read(p[0], tmp, sizeof tmp);
        if (n <= 0)
            break;
        size_t room = out_size > got + 1 ? out_size - got - 1 : 0;
        size_t take = (size_t)n < room ? (size_t)n : room;
        memcpy(out + got, tmp, take);
        got += take;
    }
    close(p[0]);
    if (out_size)
        out[got < out_size ? got : out_size - 1] = 0;
    int status = 0;
    /* Closing stdout is not exiting: keep the deadline while waiting too. */
    while (!timed_out) {
        pid_t w = waitpid(pid, &status, WNOHANG);
        if (w == pid)
            return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
        if (w < 0 && errno != EINTR)
            return -1;
        if (mt_now_ms() >= deadline)
            timed_out = 1;
        else
            mt_sleep_ms(10);
    }
    kill(pid, SIGKILL); /* our own child, by its id */
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    return -1;
}

#endif
