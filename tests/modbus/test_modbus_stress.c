/* test_modbus_stress.c: many HMIs at once. N clients (libmodbus, one thread
 * each, default 50) poll the status as input and holding registers for D
 * seconds (default 12; the 30 s run is `test_modbus_stress 30`).
 * Every request must succeed, every map version read must be 1 and each
 * client's block number must never go backwards. */
#include <modbus.h>

#include "modbus/modbus_test_util.h"
#include "test.h"

typedef struct worker {
    pthread_t thread;
    uint16_t port;
    double deadline;
    long requests;
    long errors;
    double worst_s;
} worker;

static void *poll_loop(void *arg)
{
    worker *w = arg;
    modbus_t *ctx = modbus_new_tcp("127.0.0.1", w->port);
    if (!ctx || modbus_connect(ctx) < 0) {
        w->errors++;
        if (ctx)
            modbus_free(ctx);
        return NULL;
    }
    modbus_set_response_timeout(ctx, 2, 0);
    uint32_t last_block = 0;
    int turn = 0;
    while (fm_clock_monotonic_s() < w->deadline) {
        uint16_t regs[29];
        double t0 = fm_clock_monotonic_s();
        int n = turn++ % 2 ? modbus_read_registers(ctx, 0, 29, regs) : modbus_read_input_registers(ctx, 0, 29, regs);
        double dt = fm_clock_monotonic_s() - t0;
        w->requests++;
        if (dt > w->worst_s)
            w->worst_s = dt;
        uint32_t block = (uint32_t)regs[3] << 16 | regs[4];
        if (n != 29 || regs[0] != 1 || block < last_block) {
            w->errors++;
            continue;
        }
        last_block = block;
        mt_sleep_ms(5);
    }
    modbus_close(ctx);
    modbus_free(ctx);
    return NULL;
}

int main(int argc, char **argv)
{
    double duration = argc > 1 ? atof(argv[1]) : 12.0;
    int clients = argc > 2 ? atoi(argv[2]) : 50;
    if (duration <= 0 || duration > 3600 || clients < 1 || clients > 500) {
        fprintf(stderr, "usage: test_modbus_stress [seconds 0..3600] [clients 1..500]\n");
        return 2;
    }
    mt_service svc;
    mt_service_init(&svc);
    svc.block_start_ms = mt_now_ms();
    svc.block_period_ms = 20;
    fm_modbus_service iface = mt_service_iface(&svc);
    fm_modbus_config cfg;
    fm_modbus_config_default(&cfg);
    cfg.port = 0;
    cfg.max_connections = clients + 4;
    fm_modbus_server *server;
    fm_error err;
    if (fm_modbus_server_start(&cfg, &iface, &server, &err) != FM_OK) {
        fprintf(stderr, "%s\n", err.message);
        return 1;
    }
    worker *w = calloc((size_t)clients, sizeof *w);
    double deadline = fm_clock_monotonic_s() + duration;
    int started = 0;
    for (int i = 0; i < clients; i++) {
        w[i].port = fm_modbus_server_port(server);
        w[i].deadline = deadline;
        if (pthread_create(&w[i].thread, NULL, poll_loop, &w[i]) != 0)
            break;
        started++;
    }
    CHECK(started == clients);
    long requests = 0, errors = 0;
    double worst = 0;
    for (int i = 0; i < started; i++) {
        pthread_join(w[i].thread, NULL);
        requests += w[i].requests;
        errors += w[i].errors;
        if (w[i].worst_s > worst)
            worst = w[i].worst_s;
    }
    CHECK(errors == 0);
    CHECK(requests >= (long)clients * (long)duration); /* at least 1 per client per second */
    printf("stress: %d clients, %.0f s, %ld requests (%.0f/s), %ld errors, worst latency %.2f ms\n", started,
           duration, requests, requests / duration, errors, worst * 1e3);
    free(w);
    fm_modbus_server_stop(server);
    mt_service_destroy(&svc);
    return test_summary("modbus_stress");
}
