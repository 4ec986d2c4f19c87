/* test_modbus_mbpoll.c: Debian's mbpoll (a Modbus master nobody here wrote)
 * reads the server over a fake service whose block number advances every
 * 20 ms: the status block as input and holding registers, the block number
 * advancing and the heartbeat ticking between two polls, float32 and uint32
 * in both word orders (mbpoll -B is ABCD, its default CDAB), and a write
 * refused when commands are disabled. Skips without mbpoll (test_skip). */
#include "modbus/modbus_test_util.h"
#include "test.h"

#define MAX_REF 200

typedef struct poll_result {
    int ok;
    int present[MAX_REF];
    double value[MAX_REF];
} poll_result;

/* Run mbpoll once against port with extra arguments; parse "[ref]: value". */
static void mbpoll(uint16_t port, const char *type, int ref, int count, int big_endian, poll_result *out)
{
    char port_s[16], ref_s[16], count_s[16], out_buf[16384];
    snprintf(port_s, sizeof port_s, "%u", (unsigned)port);
    snprintf(ref_s, sizeof ref_s, "%d", ref);
    snprintf(count_s, sizeof count_s, "%d", count);
    char *argv[20];
    int a = 0;
    argv[a++] = "mbpoll";
    argv[a++] = "-m";
    argv[a++] = "tcp";
    argv[a++] = "-p";
    argv[a++] = port_s;
    argv[a++] = "-a";
    argv[a++] = "1";
    argv[a++] = "-0"; /* PDU (0-based) addresses, as in the register map */
    argv[a++] = "-t";
    argv[a++] = (char *)type;
    argv[a++] = "-r";
    argv[a++] = ref_s;
    argv[a++] = "-c";
    argv[a++] = count_s;
    argv[a++] = "-1";
    argv[a++] = "-o";
    argv[a++] = "2";
    if (big_endian)
        argv[a++] = "-B";
    argv[a++] = "127.0.0.1";
    argv[a] = NULL;
    memset(out, 0, sizeof *out);
    int rc = mt_run(argv, NULL, out_buf, sizeof out_buf, 15000);
    out->ok = rc == 0;
    for (char *line = strtok(out_buf, "\n"); line; line = strtok(NULL, "\n")) {
        int r;
        double v;
        if (sscanf(line, "[%d]: %lf", &r, &v) == 2 && r >= 0 && r < MAX_REF) {
            out->present[r] = 1;
            out->value[r] = v;
        }
    }
    if (!out->ok)
        fprintf(stderr, "mbpoll -t %s -r %d exited %d\n", type, ref, rc);
}

static double rel_err(double got, double want)
{
    return fabs(got - want) / (fabs(want) > 1 ? fabs(want) : 1);
}

static fm_modbus_server *start(mt_service *svc, fm_modbus_word_order order)
{
    fm_modbus_service iface = mt_service_iface(svc);
    fm_modbus_config cfg;
    fm_modbus_config_default(&cfg);
    cfg.port = 0;
    cfg.word_order = order;
    fm_modbus_server *s = NULL;
    fm_error err;
    if (fm_modbus_server_start(&cfg, &iface, &s, &err) != FM_OK)
        fprintf(stderr, "%s\n", err.message);
    return s;
}

/* The floats at 9..22 in the fake status, in register order. */
static const double floats[7] = {12.5, -3.25, 100.125, 42.75, 1234.5, 98765.25, 0.15625};

static void check_floats(const poll_result *p)
{
    CHECK(p->ok);
    for (int k = 0; k < 7; k++) {
        int ref = 9 + 2 * k;
        CHECK(p->present[ref]);
        /* mbpoll prints %g: 6 significant digits. */
        CHECK(rel_err(p->value[ref], floats[k]) < 1e-5);
    }
}

int main(void)
{
    if (!mt_have_program("mbpoll"))
        return test_skip("modbus_mbpoll: mbpoll is not installed (Debian package mbpoll)");
    mt_service svc;
    mt_service_init(&svc);
    svc.status.first_finding_line = 3 * 65536 + 2; /* distinct words: order shows */
    svc.block_start_ms = mt_now_ms();
    svc.block_period_ms = 20;
    fm_modbus_server *abcd = start(&svc, FM_MODBUS_WORDS_ABCD);
    fm_modbus_server *cdab = start(&svc, FM_MODBUS_WORDS_CDAB);
    CHECK(abcd && cdab);
    if (!abcd || !cdab)
        return test_summary("modbus_mbpoll");
    uint16_t pa = fm_modbus_server_port(abcd), pc = fm_modbus_server_port(cdab);

    /* The status block, input registers, twice 600 ms apart. */
    poll_result r1, r2;
    double t1 = fm_clock_monotonic_s();
    mbpoll(pa, "3", 0, 29, 0, &r1);
    mt_sleep_ms(600);
    double t2 = fm_clock_monotonic_s();
    mbpoll(pa, "3", 0, 29, 0, &r2);
    CHECK(r1.ok && r2.ok);
    for (int i = 0; i < 29; i++)
        CHECK(r1.present[i] && r2.present[i]);
    CHECK(r1.value[0] == 1);                         /* map version */
    CHECK(r1.value[1] == (1 | 2 | 32));              /* loaded, running, collision */
    CHECK(r1.value[7] == 417 && r1.value[8] == 7);   /* progress, tool */
    CHECK(r1.value[23] == 3 && r1.value[27] == 2);   /* findings, slot */
    CHECK(r1.value[24] == 3 && r1.value[25] == 2);   /* ABCD: high word first */
    double block1 = r1.value[3] * 65536 + r1.value[4], block2 = r2.value[3] * 65536 + r2.value[4];
    /* One block per 20 ms since the service started; at least 600 ms apart. */
    double expect_min = 123456 + (t1 - svc.block_start_ms / 1000.0) * 50 - 5;
    CHECK(block1 >= expect_min && block1 < 123456 + 50 * 30);
    CHECK(block2 - block1 >= 600.0 / 20 - 2);
    double beats = fmod(r2.value[2] - r1.value[2] + 65536, 65536);
    CHECK(beats >= (t2 - t1) * 10 - 2 && beats <= (t2 - t1) * 10 + 10);
    printf("mbpoll: block %.0f -> %.0f, heartbeat %.0f -> %.0f over %.0f ms\n", block1, block2, r1.value[2],
           r2.value[2], (t2 - t1) * 1e3);

    /* The same as holding registers (FC03 mirror). */
    poll_result h;
    mbpoll(pa, "4", 0, 29, 0, &h);
    CHECK(h.ok && h.value[0] == 1 && h.value[8] == 7 && h.value[24] == 3 && h.value[25] == 2);

    /* Floats and uint32, ABCD server read with -B; CDAB server without. */
    poll_result f;
    mbpoll(pa, "4:float", 9, 7, 1, &f);
    check_floats(&f);
    mbpoll(pa, "3:float", 9, 7, 1, &f);
    check_floats(&f);
    mbpoll(pc, "4:float", 9, 7, 0, &f);
    check_floats(&f);
    /* The wrong word order must not read back the same values. */
    mbpoll(pc, "4:float", 9, 1, 1, &f);
    CHECK(f.ok && f.present[9] && rel_err(f.value[9], 12.5) > 0.1);

    poll_result u;
    mbpoll(pa, "3:int", 24, 1, 1, &u);
    CHECK(u.ok && u.present[24] && u.value[24] == 196610);
    mbpoll(pc, "3:int", 24, 1, 0, &u);
    CHECK(u.ok && u.present[24] && u.value[24] == 196610);
    mbpoll(pc, "4:int", 3, 1, 0, &u);
    CHECK(u.ok && u.value[3] > 123456 && u.value[3] < 123456 + 50 * 60);

    /* Commands are disabled: mbpoll's write fails (illegal data address). */
    char port_s[16], out_buf[4096];
    snprintf(port_s, sizeof port_s, "%u", (unsigned)pa);
    char *wargv[] = {"mbpoll", "-m", "tcp", "-p", port_s, "-a", "1", "-0", "-t", "4", "-r", "100", "-1",
                     "-o", "2", "127.0.0.1", "2", NULL};
    int rc = mt_run(wargv, NULL, out_buf, sizeof out_buf, 15000);
    CHECK(rc > 0);
    CHECK(svc.ncalls == 0);

    fm_modbus_server_stop(abcd);
    fm_modbus_server_stop(cdab);
    mt_service_destroy(&svc);
    return test_summary("modbus_mbpoll");
}
