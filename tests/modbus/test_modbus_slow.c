/* test_modbus_slow.c: slow clients must not delay the others. Two clients
 * trickle one byte per second (one a valid request, one the header of a
 * 260-byte frame) for D seconds (default 6) while a fast client polls every
 * 10 ms; the fast client's worst (p100) latency must stay under 50 ms. The
 * frame deadline is set long so the trickle really is in progress. At the
 * end the slow request completes and gets its correct reply. */
#include <modbus.h>

#include "modbus/modbus_test_util.h"
#include "test.h"

typedef struct trickle {
    uint16_t port;
    int seconds;
    int ok;
} trickle;

static void *trickle_loop(void *arg)
{
    trickle *t = arg;
    int valid = mt_connect(t->port);
    int big = mt_connect(t->port);
    if (valid < 0 || big < 0) {
        if (valid >= 0)
            close(valid);
        if (big >= 0)
            close(big);
        return NULL;
    }
    uint8_t req[16], pdu[5] = {0x04, 0, 8, 0, 1};
    size_t n = mt_adu(req, 0x77, pdu, 5);
    uint8_t header[7] = {0, 9, 0, 0, 0, 254, 1};
    int sent = 0;
    for (int s = 0; s < t->seconds && sent < (int)n - 1; s++, sent++) {
        if (mt_send_all(valid, req + sent, 1) != 0)
            break;
        if (s < 7 && mt_send_all(big, header + s, 1) != 0)
            break;
        mt_sleep_ms(1000);
    }
    /* The rest at once: the reply must be for this request. */
    uint8_t r[260];
    t->ok = sent >= 1 && mt_send_all(valid, req + sent, n - (size_t)sent) == 0 && mt_recv_adu(valid, r, 2000) == 11 &&
            r[0] == 0 && r[1] == 0x77 && r[10] == 7;
    close(valid);
    close(big);
    return NULL;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

int main(int argc, char **argv)
{
    int seconds = argc > 1 ? atoi(argv[1]) : 6;
    if (seconds < 2 || seconds > 11) {
        fprintf(stderr, "usage: test_modbus_slow [seconds 2..11]\n");
        return 2;
    }
    mt_service svc;
    mt_service_init(&svc);
    fm_modbus_service iface = mt_service_iface(&svc);
    fm_modbus_config cfg;
    fm_modbus_config_default(&cfg);
    cfg.port = 0;
    cfg.frame_timeout_ms = 30000;
    fm_modbus_server *server;
    fm_error err;
    if (fm_modbus_server_start(&cfg, &iface, &server, &err) != FM_OK) {
        fprintf(stderr, "%s\n", err.message);
        return 1;
    }
    uint16_t port = fm_modbus_server_port(server);
    trickle t = {port, seconds, 0};
    pthread_t th;
    CHECK(pthread_create(&th, NULL, trickle_loop, &t) == 0);

    modbus_t *ctx = modbus_new_tcp("127.0.0.1", port);
    CHECK(ctx && modbus_connect(ctx) == 0);
    modbus_set_response_timeout(ctx, 1, 0);
    static double lat[4000];
    int count = 0, errors = 0;
    double end = fm_clock_monotonic_s() + seconds - 0.5;
    mt_sleep_ms(200); /* let the tricklers connect and start */
    while (fm_clock_monotonic_s() < end && count < 4000) {
        uint16_t regs[29];
        double t0 = fm_clock_monotonic_s();
        int rc = modbus_read_input_registers(ctx, 0, 29, regs);
        lat[count++] = fm_clock_monotonic_s() - t0;
        if (rc != 29 || regs[0] != 1)
            errors++;
        mt_sleep_ms(10);
    }
    modbus_close(ctx);
    modbus_free(ctx);
    pthread_join(th, NULL);
    qsort(lat, (size_t)count, sizeof lat[0], cmp_double);
    double p50 = count ? lat[count / 2] : 0, p100 = count ? lat[count - 1] : 0;
    printf("slow clients: 2 trickling 1 byte/s for %d s; fast client %d requests, %d errors, "
           "latency p50 %.3f ms, p100 %.3f ms\n", seconds, count, errors, p50 * 1e3, p100 * 1e3);
    CHECK(count > 50 * (seconds - 1));
    CHECK(errors == 0);
    CHECK(p100 < 0.050);
    CHECK(t.ok);
    fm_modbus_server_stop(server);
    mt_service_destroy(&svc);
    return test_summary("modbus_slow");
}
