/* test_modbus_server.c: the server on ephemeral loopback ports, driven by
 * libmodbus's client and by raw sockets: start/stop, the register map over
 * TCP, refused writes, pipelined requests, the connection limit, frame and
 * idle deadlines, every attack frame, random bytes, and a client that never
 * reads its replies. */
#include <dirent.h>
#include <modbus.h>

#include "modbus/modbus_test_util.h"
#include "test.h"

typedef struct srv {
    mt_service svc;
    fm_modbus_server *server;
    uint16_t port;
} srv;

static int srv_start(srv *s, void (*tune)(fm_modbus_config *))
{
    mt_service_init(&s->svc);
    fm_modbus_config cfg;
    fm_modbus_config_default(&cfg);
    cfg.port = 0;
    if (tune)
        tune(&cfg);
    fm_modbus_service iface = mt_service_iface(&s->svc);
    fm_error err;
    fm_error_clear(&err);
    if (fm_modbus_server_start(&cfg, &iface, &s->server, &err) != FM_OK) {
        fprintf(stderr, "server start: %s\n", err.message);
        return -1;
    }
    s->port = fm_modbus_server_port(s->server);
    return 0;
}

static void srv_stop(srv *s)
{
    fm_modbus_server_stop(s->server);
    mt_service_destroy(&s->svc);
}

static modbus_t *client(uint16_t port)
{
    modbus_t *ctx = modbus_new_tcp("127.0.0.1", port);
    if (!ctx)
        return NULL;
    modbus_set_response_timeout(ctx, 2, 0);
    if (modbus_connect(ctx) < 0) {
        modbus_free(ctx);
        return NULL;
    }
    return ctx;
}

static void client_close(modbus_t *ctx)
{
    if (ctx) {
        modbus_close(ctx);
        modbus_free(ctx);
    }
}

static void test_start_stop(void)
{
    srv a, b;
    CHECK(srv_start(&a, NULL) == 0);
    CHECK(srv_start(&b, NULL) == 0);
    CHECK(a.port != 0 && b.port != 0 && a.port != b.port);
    srv_stop(&a);
    srv_stop(&b);

    mt_service m;
    mt_service_init(&m);
    fm_modbus_service iface = mt_service_iface(&m);
    fm_modbus_config cfg;
    fm_modbus_config_default(&cfg);
    CHECK(cfg.port == 1502 && strcmp(cfg.listen_addr, "127.0.0.1") == 0 && cfg.enable_commands == 0 &&
          cfg.enable_live == 0);
    cfg.port = 0;
    snprintf(cfg.listen_addr, sizeof cfg.listen_addr, "localhost");
    fm_modbus_server *s = (fm_modbus_server *)&m; /* must be reset to NULL */
    fm_error err;
    CHECK(fm_modbus_server_start(&cfg, &iface, &s, &err) == FM_ERR_INPUT && s == NULL);
    CHECK_STR_CONTAINS(err.message, "localhost");
    snprintf(cfg.listen_addr, sizeof cfg.listen_addr, "127.0.0.1");
    cfg.max_connections = 0;
    CHECK(fm_modbus_server_start(&cfg, &iface, &s, &err) == FM_ERR_INPUT);
    cfg.max_connections = 4;
    cfg.enable_live = 1;
    iface.live_position = NULL;
    CHECK(fm_modbus_server_start(&cfg, &iface, &s, &err) == FM_ERR_INPUT);
    fm_modbus_server_stop(NULL);
    mt_service_destroy(&m);
}

static void test_map_over_tcp(void)
{
    srv s;
    if (srv_start(&s, NULL) != 0) {
        CHECK(0);
        return;
    }
    modbus_t *ctx = client(s.port);
    CHECK(ctx != NULL);
    if (ctx) {
        uint16_t in[29], hold[29];
        CHECK(modbus_read_input_registers(ctx, 0, 29, in) == 29);
        CHECK(modbus_read_registers(ctx, 0, 29, hold) == 29);
        CHECK(in[0] == 1 && in[1] == (1 | 2 | 32));
        CHECK(in[3] == 1 && in[4] == 57920); /* 123456, high word first */
        CHECK(in[8] == 7 && in[27] == 2);
        CHECK(in[9] == 0x4148 && in[10] == 0x0000); /* 12.5f = 0x41480000 */
        /* The mirror differs at most in the heartbeat (a tick between reads). */
        CHECK(memcmp(in, hold, 4) == 0 && memcmp(in + 3, hold + 3, 26 * 2) == 0);

        uint16_t one;
        errno = 0;
        CHECK(modbus_write_register(ctx, 100, 2) == -1 && errno == EMBXILADD);
        errno = 0;
        CHECK(modbus_read_input_registers(ctx, 29, 1, &one) == -1 && errno == EMBXILADD);
        uint8_t bits[8];
        errno = 0;
        CHECK(modbus_read_bits(ctx, 0, 8, bits) == -1 && errno == EMBXILFUN);

        /* The heartbeat ticks every 100 ms: 5 or 6 ticks in 550 ms, allowing
         * for scheduling jitter on a loaded machine. */
        uint16_t hb0, hb1;
        CHECK(modbus_read_input_registers(ctx, 2, 1, &hb0) == 1);
        double t0 = fm_clock_monotonic_s();
        mt_sleep_ms(550);
        CHECK(modbus_read_input_registers(ctx, 2, 1, &hb1) == 1);
        double dt = fm_clock_monotonic_s() - t0;
        int ticks = (uint16_t)(hb1 - hb0);
        int expected = (int)(dt * 10);
        CHECK(ticks >= expected - 1 && ticks <= expected + 2);
    }
    client_close(ctx);
    CHECK(s.svc.ncalls == 0);
    srv_stop(&s);
}

static void tune_commands(fm_modbus_config *c)
{
    c->enable_commands = 1;
    c->word_order = FM_MODBUS_WORDS_CDAB;
}

static void test_commands_over_tcp(void)
{
    srv s;
    if (srv_start(&s, tune_commands) != 0) {
        CHECK(0);
        return;
    }
    modbus_t *ctx = client(s.port);
    CHECK(ctx != NULL);
    if (ctx) {
        uint16_t cmd[3] = {FM_MODBUS_CMD_PAUSE, 1, 3};
        CHECK(modbus_write_registers(ctx, 100, 3, cmd) == 3);
        CHECK(modbus_write_registers(ctx, 100, 3, cmd) == 3);
        uint16_t ack;
        CHECK(modbus_read_registers(ctx, 28, 1, &ack) == 1 && ack == 1);
        CHECK(mt_count_calls(&s.svc, 'c') == 1);
        uint16_t in[2];
        /* CDAB: 123456 = 0x0001E240 is sent low word first. */
        CHECK(modbus_read_input_registers(ctx, 3, 2, in) == 2 && in[0] == 57920 && in[1] == 1);
    }
    client_close(ctx);
    srv_stop(&s);
}

static void test_pipelined(void)
{
    srv s;
    if (srv_start(&s, NULL) != 0) {
        CHECK(0);
        return;
    }
    int fd = mt_connect(s.port);
    CHECK(fd >= 0);
    uint8_t stream[64], pdu[5] = {0x04, 0, 8, 0, 1};
    size_t n = 0;
    for (unsigned tid = 1; tid <= 3; tid++)
        n += mt_adu(stream + n, tid, pdu, 5);
    CHECK(mt_send_all(fd, stream, n) == 0);
    for (unsigned tid = 1; tid <= 3; tid++) {
        uint8_t r[260];
        int len = mt_recv_adu(fd, r, 2000);
        CHECK(len == 11 && r[1] == tid && r[7] == 4 && r[9] == 0 && r[10] == 7);
    }
    close(fd);
    srv_stop(&s);
}

static int read_ok(int fd, unsigned tid)
{
    uint8_t req[16], r[260], pdu[5] = {0x04, 0, 0, 0, 1};
    size_t n = mt_adu(req, tid, pdu, 5);
    if (mt_send_all(fd, req, n) != 0)
        return 0;
    return mt_recv_adu(fd, r, 2000) == 11 && r[10] == 1;
}

static void tune_limits(fm_modbus_config *c)
{
    c->max_connections = 4;
    c->frame_timeout_ms = 300;
    c->idle_timeout_ms = 800;
}

static void test_limits_and_deadlines(void)
{
    srv s;
    if (srv_start(&s, tune_limits) != 0) {
        CHECK(0);
        return;
    }
    int fds[4];
    for (int i = 0; i < 4; i++) {
        fds[i] = mt_connect(s.port);
        CHECK(fds[i] >= 0 && read_ok(fds[i], (unsigned)i));
    }
    /* The fifth is accepted by the kernel, then closed by the server. */
    int extra = mt_connect(s.port);
    CHECK(extra >= 0 && mt_wait_closed(extra, 2000) == 1);
    close(extra);
    close(fds[0]);
    int ok = 0;
    for (int attempt = 0; attempt < 20 && !ok; attempt++) {
        mt_sleep_ms(50);
        int fd = mt_connect(s.port);
        ok = fd >= 0 && read_ok(fd, 9);
        fds[0] = fd;
    }
    CHECK(ok);
    for (int i = 0; i < 4; i++)
        close(fds[i]);

    /* A frame that never completes is closed at the frame deadline (300 ms). */
    mt_sleep_ms(100);
    int fd = mt_connect(s.port);
    uint8_t part[3] = {0, 1, 0};
    CHECK(fd >= 0 && mt_send_all(fd, part, 3) == 0);
    double t0 = fm_clock_monotonic_s();
    CHECK(mt_wait_closed(fd, 3000) == 1);
    double dt = fm_clock_monotonic_s() - t0;
    CHECK(dt >= 0.25 && dt < 1.5);
    close(fd);

    /* A silent connection is closed at the idle deadline (800 ms). */
    fd = mt_connect(s.port);
    CHECK(fd >= 0);
    t0 = fm_clock_monotonic_s();
    CHECK(mt_wait_closed(fd, 5000) == 1);
    dt = fm_clock_monotonic_s() - t0;
    CHECK(dt >= 0.7 && dt < 2.5);
    close(fd);
    srv_stop(&s);
}

static void tune_attacks(fm_modbus_config *c)
{
    c->enable_commands = 1;
    c->enable_live = 1;
    c->frame_timeout_ms = 300;
    c->max_connections = 8;
}

static void test_attacks_over_tcp(void)
{
    srv s;
    if (srv_start(&s, tune_attacks) != 0) {
        CHECK(0);
        return;
    }
    modbus_t *healthy = client(s.port);
    CHECK(healthy != NULL);
    DIR *d = opendir("modbus/attacks");
    CHECK(d != NULL);
    int count = 0;
    struct dirent *e;
    while (d && (e = readdir(d)) != NULL) {
        size_t n = strlen(e->d_name);
        if (n < 5 || strcmp(e->d_name + n - 4, ".hex") != 0)
            continue;
        char path[512];
        snprintf(path, sizeof path, "modbus/attacks/%s", e->d_name);
        mt_attack a;
        if (mt_attack_load(path, e->d_name, &a) != 0) {
            CHECK(0);
            continue;
        }
        count++;
        int fd = mt_connect(s.port);
        CHECK(fd >= 0);
        if (fd < 0)
            continue;
        CHECK(mt_send_all(fd, a.bytes, a.len) == 0);
        int ok = 0;
        uint8_t r[260];
        if (a.expect == MT_EXPECT_EXCEPTION) {
            int len = mt_recv_adu(fd, r, 2000);
            ok = len == 9 && r[7] == (a.bytes[7] | 0x80) && r[8] == a.code && memcmp(r, a.bytes, 4) == 0;
        } else if (a.expect == MT_EXPECT_CLOSE) {
            ok = mt_wait_closed(fd, 2000) == 1;
        } else {
            struct pollfd p = {fd, POLLIN, 0};
            ok = poll(&p, 1, 100) == 0 && mt_wait_closed(fd, 3000) == 1;
        }
        if (!ok)
            fprintf(stderr, "attack %s over TCP: unexpected outcome\n", a.name);
        CHECK(ok);
        close(fd);
        uint16_t v;
        CHECK(healthy && modbus_read_input_registers(healthy, 0, 1, &v) == 1 && v == 1);
    }
    if (d)
        closedir(d);
    CHECK(count >= 30);
    CHECK(mt_count_calls(&s.svc, 'c') == 0 && mt_count_calls(&s.svc, 'p') == 0);
    client_close(healthy);
    srv_stop(&s);
}

static void tune_random(fm_modbus_config *c)
{
    c->frame_timeout_ms = 200;
    c->max_connections = 32;
}

static void test_random_bytes(void)
{
    srv s;
    if (srv_start(&s, tune_random) != 0) {
        CHECK(0);
        return;
    }
    int replies = 0;
    for (int i = 0; i < 300; i++) {
        int fd = mt_connect(s.port);
        CHECK(fd >= 0);
        if (fd < 0)
            break;
        uint8_t buf[700];
        size_t n = 1 + (size_t)(test_rand01() * (sizeof buf - 1));
        for (size_t k = 0; k < n; k++)
            buf[k] = (uint8_t)(test_rand01() * 256);
        if (i % 2 == 0 && n >= 8) { /* half get a plausible header */
            buf[2] = buf[3] = 0;
            buf[4] = 0;
            buf[5] = (uint8_t)(2 + test_rand01() * 20);
        }
        mt_send_all(fd, buf, n); /* the server may already have closed */
        if (i % 3 == 0) {
            uint8_t r[260];
            if (mt_recv_adu(fd, r, 50) > 0)
                replies++;
        }
        close(fd);
    }
    modbus_t *ctx = client(s.port);
    uint16_t v;
    CHECK(ctx && modbus_read_input_registers(ctx, 0, 1, &v) == 1 && v == 1);
    client_close(ctx);
    CHECK(s.svc.ncalls == 0);
    printf("random bytes: 300 connections, %d exception or data replies seen\n", replies);
    srv_stop(&s);
}

static void tune_nonreader(fm_modbus_config *c)
{
    c->idle_timeout_ms = 1000;
}

/* A client that sends requests and never reads: the server stops reading it
 * once its replies back up, serves the others, and drops it when idle. */
static void test_non_reader(void)
{
    srv s;
    if (srv_start(&s, tune_nonreader) != 0) {
        CHECK(0);
        return;
    }
    int bad = mt_connect(s.port);
    CHECK(bad >= 0);
    int small = 4096;
    setsockopt(bad, SOL_SOCKET, SO_RCVBUF, &small, sizeof small);
    setsockopt(bad, SOL_SOCKET, SO_SNDBUF, &small, sizeof small);
    fcntl(bad, F_SETFL, fcntl(bad, F_GETFL) | O_NONBLOCK);
    uint8_t req[16], pdu[5] = {0x03, 0, 0, 0, 29};
    size_t n = mt_adu(req, 1, pdu, 5);
    /* Keep sending until the pipe stays full for 300 ms: by then every buffer
     * between us is full and the server has stopped reading this client. */
    int sent = 0, stuck = 0;
    size_t partial = 0;
    int64_t full_since = 0, give_up = mt_now_ms() + 20000;
    while (mt_now_ms() < give_up) {
        ssize_t w = send(bad, req + partial, n - partial, MSG_NOSIGNAL);
        if (w > 0) {
            partial += (size_t)w;
            if (partial == n) {
                partial = 0;
                sent++;
            }
            full_since = 0;
            continue;
        }
        if (w < 0 && errno != EAGAIN && errno != EWOULDBLOCK)
            break;
        if (full_since == 0)
            full_since = mt_now_ms();
        else if (mt_now_ms() - full_since > 300) {
            stuck = 1;
            break;
        }
        mt_sleep_ms(5);
    }
    CHECK(stuck);
    modbus_t *ctx = client(s.port);
    CHECK(ctx != NULL);
    double worst = 0;
    for (int i = 0; ctx && i < 20; i++) {
        uint16_t v;
        double t0 = fm_clock_monotonic_s();
        CHECK(modbus_read_input_registers(ctx, 0, 1, &v) == 1);
        double dt = fm_clock_monotonic_s() - t0;
        if (dt > worst)
            worst = dt;
    }
    CHECK(worst < 0.05);
    printf("non-reader: %d requests queued unread; other client's worst latency %.2f ms\n", sent,
           worst * 1e3);
    client_close(ctx);
    /* The server drops it at the idle deadline with a reset; without reading
     * (which would count as progress), a send sees it. */
    int closed = 0;
    for (int i = 0; i < 50 && !closed; i++) {
        mt_sleep_ms(100);
        ssize_t w = send(bad, req, 1, MSG_NOSIGNAL);
        closed = w < 0 && errno != EAGAIN && errno != EWOULDBLOCK;
    }
    CHECK(closed);
    close(bad);
    srv_stop(&s);
}

int main(void)
{
    signal(SIGPIPE, SIG_IGN);
    test_start_stop();
    test_map_over_tcp();
    test_commands_over_tcp();
    test_pipelined();
    test_limits_and_deadlines();
    test_attacks_over_tcp();
    test_random_bytes();
    test_non_reader();
    return test_summary("modbus_server");
}
