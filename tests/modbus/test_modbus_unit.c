/* test_modbus_unit.c: the Modbus engine frame by frame, with no sockets: word
 * packing, framing, the register map, exceptions, command sequence numbers,
 * the HMI watchdog, live mode, every attack frame under tests/modbus/attacks,
 * and random frames. Expected register values are computed here from the
 * fake status (IEEE bits by frexp, not by the code under test). */
#include <dirent.h>
#include <math.h>

#include "modbus/modbus_test_util.h"
#include "protocols/modbus/modbus_internal.h"
#include "test.h"

/* IEEE 754 single bits of v, computed arithmetically (normal numbers, round
 * to nearest even), independently of memcpy-based packing. */
static uint32_t ieee_bits(double v)
{
    if (v == 0)
        return signbit(v) ? 0x80000000u : 0;
    uint32_t sign = v < 0 ? 0x80000000u : 0;
    int e;
    double m = frexp(fabs(v), &e); /* v = m * 2^e, 0.5 <= m < 1 */
    double frac = nearbyint((m * 2.0 - 1.0) * 8388608.0);
    int exp = e - 1 + 127;
    if (frac >= 8388608.0) { /* rounding carried into the exponent */
        frac = 0;
        exp++;
    }
    return sign | ((uint32_t)exp << 23) | (uint32_t)frac;
}

static void test_packing(void)
{
    uint16_t w[2];
    fm_modbus_pack_u32(0x12345678u, FM_MODBUS_WORDS_ABCD, w);
    CHECK(w[0] == 0x1234 && w[1] == 0x5678);
    fm_modbus_pack_u32(0x12345678u, FM_MODBUS_WORDS_CDAB, w);
    CHECK(w[0] == 0x5678 && w[1] == 0x1234);
    CHECK(fm_modbus_unpack_u32(w, FM_MODBUS_WORDS_CDAB) == 0x12345678u);

    /* Constants from the IEEE 754 tables, then the arithmetic reference. */
    fm_modbus_pack_f32(1.0, FM_MODBUS_WORDS_ABCD, w);
    CHECK(w[0] == 0x3F80 && w[1] == 0x0000);
    fm_modbus_pack_f32(-2.0, FM_MODBUS_WORDS_ABCD, w);
    CHECK(w[0] == 0xC000 && w[1] == 0x0000);
    fm_modbus_pack_f32(0.15625, FM_MODBUS_WORDS_CDAB, w);
    CHECK(w[0] == 0x0000 && w[1] == 0x3E20);
    fm_modbus_pack_f32(1e300, FM_MODBUS_WORDS_ABCD, w);
    CHECK(w[0] == 0x7F80 && w[1] == 0x0000);
    fm_modbus_pack_f32(-1e300, FM_MODBUS_WORDS_ABCD, w);
    CHECK(w[0] == 0xFF80 && w[1] == 0x0000);
    fm_modbus_pack_f32(NAN, FM_MODBUS_WORDS_ABCD, w);
    CHECK(isnan(fm_modbus_unpack_f32(w, FM_MODBUS_WORDS_ABCD)));

    const double values[] = {12.5, -3.25, 100.125, 0.1, -1234.5678, 3.0e-30, 6.02e23, 65535.0};
    for (size_t i = 0; i < sizeof values / sizeof values[0]; i++) {
        for (int o = 0; o < 2; o++) {
            fm_modbus_pack_f32(values[i], (fm_modbus_word_order)o, w);
            uint32_t want = ieee_bits(values[i]);
            uint16_t hi = o ? w[1] : w[0], lo = o ? w[0] : w[1];
            CHECK(hi == want >> 16 && lo == (want & 0xFFFF));
            CHECK((double)fm_modbus_unpack_f32(w, (fm_modbus_word_order)o) == (double)(float)values[i]);
        }
    }
}

static void test_framing(void)
{
    uint8_t b[8] = {0, 1, 0, 0, 0, 6, 1, 3};
    for (size_t have = 0; have < 7; have++)
        CHECK(fm_modbus_frame_length(b, have) == 0);
    CHECK(fm_modbus_frame_length(b, 7) == 12);
    b[5] = 254;
    CHECK(fm_modbus_frame_length(b, 7) == 260);
    b[5] = 255;
    CHECK(fm_modbus_frame_length(b, 7) == -1);
    b[5] = 1;
    CHECK(fm_modbus_frame_length(b, 7) == -1);
    b[5] = 6;
    b[3] = 1;
    CHECK(fm_modbus_frame_length(b, 7) == -1);
}

/* Engine, fake service and a reply buffer for the frame tests. */
typedef struct rig {
    mt_service svc;
    fm_modbus_service iface;
    fm_modbus_engine eng;
    uint8_t reply[FM_MODBUS_MAX_ADU];
    size_t reply_len;
} rig;

static void rig_init(rig *r, int commands, int live, int watchdog_ms, fm_modbus_word_order order)
{
    memset(r, 0, sizeof *r);
    mt_service_init(&r->svc);
    r->iface = mt_service_iface(&r->svc);
    fm_modbus_config cfg;
    fm_modbus_config_default(&cfg);
    cfg.enable_commands = commands;
    cfg.enable_live = live;
    cfg.watchdog_ms = watchdog_ms;
    cfg.word_order = order;
    fm_modbus_engine_init(&r->eng, &cfg, &r->iface, 1000);
}

static size_t rig_send(rig *r, const uint8_t *pdu, size_t pdu_len)
{
    uint8_t adu[FM_MODBUS_MAX_ADU + 16];
    size_t n = mt_adu(adu, 0x4242, pdu, pdu_len);
    memset(r->reply, 0xEE, sizeof r->reply);
    r->reply_len = fm_modbus_engine_handle(&r->eng, adu, n, r->reply);
    return r->reply_len;
}

static unsigned reg_at(const rig *r, unsigned i)
{
    return ((unsigned)r->reply[9 + 2 * i] << 8) | r->reply[10 + 2 * i];
}

static int is_exception(const rig *r, unsigned fc, unsigned code)
{
    return r->reply_len == 9 && r->reply[0] == 0x42 && r->reply[1] == 0x42 && r->reply[4] == 0 &&
           r->reply[5] == 3 && r->reply[7] == (fc | 0x80) && r->reply[8] == code;
}

static size_t read_pdu(uint8_t *pdu, unsigned fc, unsigned start, unsigned count)
{
    pdu[0] = (uint8_t)fc;
    pdu[1] = (uint8_t)(start >> 8);
    pdu[2] = (uint8_t)start;
    pdu[3] = (uint8_t)(count >> 8);
    pdu[4] = (uint8_t)count;
    return 5;
}

static size_t write_pdu(uint8_t *pdu, unsigned start, const uint16_t *vals, unsigned count)
{
    pdu[0] = 0x10;
    pdu[1] = (uint8_t)(start >> 8);
    pdu[2] = (uint8_t)start;
    pdu[3] = 0;
    pdu[4] = (uint8_t)count;
    pdu[5] = (uint8_t)(2 * count);
    for (unsigned i = 0; i < count; i++) {
        pdu[6 + 2 * i] = (uint8_t)(vals[i] >> 8);
        pdu[7 + 2 * i] = (uint8_t)vals[i];
    }
    return 6 + 2 * count;
}

static double float_at(const rig *r, unsigned i, fm_modbus_word_order o)
{
    unsigned a = reg_at(r, i), b = reg_at(r, i + 1);
    uint32_t bits = o == FM_MODBUS_WORDS_ABCD ? (a << 16 | b) : (b << 16 | a);
    float f;
    memcpy(&f, &bits, 4);
    return f;
}

static void test_status_map(fm_modbus_word_order o)
{
    rig r;
    rig_init(&r, 0, 0, 0, o);
    uint8_t pdu[300];
    CHECK(rig_send(&r, pdu, read_pdu(pdu, 0x04, 0, 29)) == 9 + 58);
    CHECK(r.reply[7] == 0x04 && r.reply[8] == 58 && r.reply[5] == 3 + 58);
    CHECK(reg_at(&r, 0) == 1);
    CHECK(reg_at(&r, 1) == (1u | 2u | 32u));
    CHECK(reg_at(&r, 2) == 0);
    unsigned hi = o == FM_MODBUS_WORDS_ABCD ? 0 : 1;
    /* 123456 = 1 * 65536 + 57920 */
    CHECK(reg_at(&r, 3 + hi) == 1 && reg_at(&r, 4 - hi) == 57920);
    /* 70000 = 1 * 65536 + 4464 */
    CHECK(reg_at(&r, 5 + hi) == 1 && reg_at(&r, 6 - hi) == 4464);
    CHECK(reg_at(&r, 7) == 417);
    CHECK(reg_at(&r, 8) == 7);
    CHECK(float_at(&r, 9, o) == 12.5);
    CHECK(float_at(&r, 11, o) == -3.25);
    CHECK(float_at(&r, 13, o) == 100.125);
    CHECK(float_at(&r, 15, o) == 42.75);
    CHECK(float_at(&r, 17, o) == 1234.5);
    CHECK(float_at(&r, 19, o) == 98765.25);
    CHECK(float_at(&r, 21, o) == 0.15625);
    CHECK(reg_at(&r, 23) == 3);
    CHECK(reg_at(&r, 24 + hi) == 1 && reg_at(&r, 25 - hi) == 1);
    CHECK(reg_at(&r, 26) == 0);
    CHECK(reg_at(&r, 27) == 2);
    CHECK(reg_at(&r, 28) == 0);

    /* FC03 mirrors FC04 at the same addresses. */
    uint8_t input[60];
    memcpy(input, r.reply + 9, 58);
    CHECK(rig_send(&r, pdu, read_pdu(pdu, 0x03, 0, 29)) == 9 + 58);
    CHECK(r.reply[7] == 0x03 && memcmp(input, r.reply + 9, 58) == 0);
    /* A single register in the middle. */
    CHECK(rig_send(&r, pdu, read_pdu(pdu, 0x03, 8, 1)) == 11);
    CHECK(reg_at(&r, 0) == 7);

    /* Outside the map. */
    rig_send(&r, pdu, read_pdu(pdu, 0x04, 29, 1));
    CHECK(is_exception(&r, 0x04, 2));
    rig_send(&r, pdu, read_pdu(pdu, 0x04, 100, 1)); /* commands are holding only */
    CHECK(is_exception(&r, 0x04, 2));
    rig_send(&r, pdu, read_pdu(pdu, 0x03, 28, 2));
    CHECK(is_exception(&r, 0x03, 2));
    rig_send(&r, pdu, read_pdu(pdu, 0x03, 99, 2));
    CHECK(is_exception(&r, 0x03, 2));
    rig_send(&r, pdu, read_pdu(pdu, 0x03, 104, 1));
    CHECK(is_exception(&r, 0x03, 2));
    rig_send(&r, pdu, read_pdu(pdu, 0x03, 118, 1));
    CHECK(is_exception(&r, 0x03, 2));
    /* Commands and live registers read back (zero) even when not writable. */
    CHECK(rig_send(&r, pdu, read_pdu(pdu, 0x03, 100, 4)) == 17);
    CHECK(rig_send(&r, pdu, read_pdu(pdu, 0x03, 110, 8)) == 25);
    /* Unsupported function codes. */
    uint8_t coils[5] = {0x01, 0, 0, 0, 1};
    rig_send(&r, coils, 5);
    CHECK(is_exception(&r, 0x01, 1));
    mt_service_destroy(&r.svc);
}

static void test_heartbeat(void)
{
    rig r;
    rig_init(&r, 0, 0, 0, FM_MODBUS_WORDS_ABCD);
    uint8_t pdu[8];
    CHECK(fm_modbus_engine_tick(&r.eng, 1099) == 1);
    rig_send(&r, pdu, read_pdu(pdu, 0x04, 2, 1));
    CHECK(reg_at(&r, 0) == 0);
    CHECK(fm_modbus_engine_tick(&r.eng, 1350) == 50); /* ticks at 1100, 1200, 1300 */
    rig_send(&r, pdu, read_pdu(pdu, 0x04, 2, 1));
    CHECK(reg_at(&r, 0) == 3);
    r.eng.heartbeat = 0xFFFF; /* the register wraps */
    fm_modbus_engine_tick(&r.eng, 1400);
    rig_send(&r, pdu, read_pdu(pdu, 0x03, 2, 1));
    CHECK(reg_at(&r, 0) == 0);
    mt_service_destroy(&r.svc);
}

static void test_writes_refused(void)
{
    rig r;
    rig_init(&r, 0, 0, 0, FM_MODBUS_WORDS_ABCD);
    uint8_t pdu[300];
    uint16_t vals[8] = {2, 1, 0, 1, 0, 0, 0, 1};
    uint8_t single[5] = {0x06, 0, 100, 0, 2};
    rig_send(&r, single, 5);
    CHECK(is_exception(&r, 0x06, 2));
    rig_send(&r, pdu, write_pdu(pdu, 100, vals, 3));
    CHECK(is_exception(&r, 0x10, 2));
    rig_send(&r, pdu, write_pdu(pdu, 110, vals, 8));
    CHECK(is_exception(&r, 0x10, 2));
    rig_send(&r, pdu, write_pdu(pdu, 0, vals, 1));
    CHECK(is_exception(&r, 0x10, 2));
    CHECK(r.svc.ncalls == 0);
    /* Nothing changed. */
    rig_send(&r, pdu, read_pdu(pdu, 0x03, 100, 4));
    CHECK(reg_at(&r, 0) == 0 && reg_at(&r, 1) == 0);

    /* Commands enabled, live not: live writes still refused. */
    rig r2;
    rig_init(&r2, 1, 0, 0, FM_MODBUS_WORDS_ABCD);
    rig_send(&r2, pdu, write_pdu(pdu, 110, vals, 8));
    CHECK(is_exception(&r2, 0x10, 2));
    rig_send(&r2, pdu, write_pdu(pdu, 100, vals, 5)); /* 100..104: past the block */
    CHECK(is_exception(&r2, 0x10, 2));
    CHECK(r2.svc.ncalls == 0);
    mt_service_destroy(&r.svc);
    mt_service_destroy(&r2.svc);
}

static void test_commands(void)
{
    rig r;
    rig_init(&r, 1, 0, 0, FM_MODBUS_WORDS_ABCD);
    uint8_t pdu[300];
    uint16_t pause1[3] = {FM_MODBUS_CMD_PAUSE, 1, 7};
    CHECK(rig_send(&r, pdu, write_pdu(pdu, 100, pause1, 3)) == 12);
    /* The FC16 reply echoes address and quantity. */
    CHECK(r.reply[7] == 0x10 && r.reply[8] == 0 && r.reply[9] == 100 && r.reply[10] == 0 && r.reply[11] == 3);
    CHECK(r.svc.ncalls == 1 && r.svc.calls[0].kind == 'c' && r.svc.calls[0].command == FM_MODBUS_CMD_PAUSE &&
          r.svc.calls[0].argument == 7);
    rig_send(&r, pdu, read_pdu(pdu, 0x04, 26, 3));
    CHECK(reg_at(&r, 0) == 0 && reg_at(&r, 2) == 1);

    /* The same sequence number again: no action, even with another command. */
    rig_send(&r, pdu, write_pdu(pdu, 100, pause1, 3));
    uint16_t start_same[2] = {FM_MODBUS_CMD_START, 1};
    rig_send(&r, pdu, write_pdu(pdu, 100, start_same, 2));
    CHECK(r.svc.ncalls == 1);

    /* A new number acts once. */
    uint16_t start2[2] = {FM_MODBUS_CMD_START, 2};
    rig_send(&r, pdu, write_pdu(pdu, 100, start2, 2));
    CHECK(r.svc.ncalls == 2 && r.svc.calls[1].command == FM_MODBUS_CMD_START && r.svc.calls[1].argument == 7);

    /* FC06 one register at a time: command, then argument, then the number. */
    uint8_t w100[5] = {0x06, 0, 100, 0, FM_MODBUS_CMD_SELECT};
    uint8_t w102[5] = {0x06, 0, 102, 0, 5};
    uint8_t w101[5] = {0x06, 0, 101, 0x12, 0x34};
    CHECK(rig_send(&r, w100, 5) == 12 && memcmp(r.reply + 7, w100, 5) == 0);
    rig_send(&r, w102, 5);
    CHECK(r.svc.ncalls == 2);
    rig_send(&r, w101, 5);
    CHECK(r.svc.ncalls == 3 && r.svc.calls[2].command == FM_MODBUS_CMD_SELECT && r.svc.calls[2].argument == 5);
    rig_send(&r, pdu, read_pdu(pdu, 0x03, 28, 1));
    CHECK(reg_at(&r, 0) == 0x1234);

    /* A refused command shows its error at 26 and is still acknowledged. */
    r.svc.command_refusal = "bad_slot";
    uint16_t sel3[3] = {FM_MODBUS_CMD_SELECT, 3, 99};
    rig_send(&r, pdu, write_pdu(pdu, 100, sel3, 3));
    rig_send(&r, pdu, read_pdu(pdu, 0x03, 26, 3));
    CHECK(reg_at(&r, 0) == FM_MODBUS_ERR_BAD_SLOT && reg_at(&r, 2) == 3);
    /* An unknown command never reaches the service. */
    r.svc.command_refusal = NULL;
    uint16_t unknown[2] = {9, 4};
    rig_send(&r, pdu, write_pdu(pdu, 100, unknown, 2));
    CHECK(r.svc.ncalls == 4);
    rig_send(&r, pdu, read_pdu(pdu, 0x03, 26, 3));
    CHECK(reg_at(&r, 0) == FM_MODBUS_ERR_UNKNOWN_COMMAND && reg_at(&r, 2) == 4);
    /* A later success clears it. */
    uint16_t ok5[2] = {FM_MODBUS_CMD_PAUSE, 5};
    rig_send(&r, pdu, write_pdu(pdu, 100, ok5, 2));
    rig_send(&r, pdu, read_pdu(pdu, 0x03, 26, 1));
    CHECK(reg_at(&r, 0) == 0);

    /* The job's own error shows when the daemon reports it. */
    r.svc.status.last_error = FM_MODBUS_ERR_JOB_INPUT;
    rig_send(&r, pdu, read_pdu(pdu, 0x04, 26, 1));
    CHECK(reg_at(&r, 0) == FM_MODBUS_ERR_JOB_INPUT);

    /* FC23: write the command block and read the acknowledgement back. */
    uint8_t wr[15] = {0x17, 0, 26, 0, 3, 0, 100, 0, 2, 4, 0, FM_MODBUS_CMD_CANCEL, 0, 6};
    CHECK(rig_send(&r, wr, 14) == 9 + 6);
    CHECK(r.reply[7] == 0x17 && r.reply[8] == 6 && reg_at(&r, 2) == 6);
    CHECK(r.svc.ncalls == 6 && r.svc.calls[5].command == FM_MODBUS_CMD_CANCEL);
    mt_service_destroy(&r.svc);
}

static void test_watchdog(void)
{
    rig r;
    rig_init(&r, 1, 0, 500, FM_MODBUS_WORDS_ABCD);
    uint8_t pdu[16];
    /* Never written: never fires. */
    fm_modbus_engine_tick(&r.eng, 10000);
    CHECK(mt_count_calls(&r.svc, 'w') == 0);
    uint8_t w1[5] = {0x06, 0, 103, 0, 1};
    rig_send(&r, w1, 5); /* at t = 10000 */
    fm_modbus_engine_tick(&r.eng, 10499);
    CHECK(mt_count_calls(&r.svc, 'w') == 0);
    fm_modbus_engine_tick(&r.eng, 10500);
    CHECK(mt_count_calls(&r.svc, 'w') == 1);
    fm_modbus_engine_tick(&r.eng, 20000);
    CHECK(mt_count_calls(&r.svc, 'w') == 1); /* once per expiry */
    rig_send(&r, pdu, read_pdu(pdu, 0x04, 26, 1));
    CHECK(reg_at(&r, 0) == FM_MODBUS_ERR_WATCHDOG);
    rig_send(&r, w1, 5); /* the same value is not a sign of life */
    fm_modbus_engine_tick(&r.eng, 30000);
    CHECK(mt_count_calls(&r.svc, 'w') == 1);
    uint8_t w2[5] = {0x06, 0, 103, 0, 2};
    rig_send(&r, w2, 5); /* t = 30000 */
    fm_modbus_engine_tick(&r.eng, 30300);
    uint8_t w3[5] = {0x06, 0, 103, 0, 3};
    rig_send(&r, w3, 5); /* alive at 30300: the next deadline is 30800 */
    fm_modbus_engine_tick(&r.eng, 30700);
    CHECK(mt_count_calls(&r.svc, 'w') == 1);
    fm_modbus_engine_tick(&r.eng, 30800);
    CHECK(mt_count_calls(&r.svc, 'w') == 2);
    mt_service_destroy(&r.svc);
}

static void pack_live(uint16_t regs[8], double x, double y, double z, int tool, int on, fm_modbus_word_order o)
{
    const double v[3] = {x, y, z};
    for (int k = 0; k < 3; k++) {
        uint32_t bits = ieee_bits(v[k]);
        uint16_t hi = (uint16_t)(bits >> 16), lo = (uint16_t)bits;
        regs[2 * k] = o == FM_MODBUS_WORDS_ABCD ? hi : lo;
        regs[2 * k + 1] = o == FM_MODBUS_WORDS_ABCD ? lo : hi;
    }
    regs[6] = (uint16_t)tool;
    regs[7] = (uint16_t)on;
}

static void test_live(fm_modbus_word_order o)
{
    rig r;
    rig_init(&r, 0, 1, 0, o);
    uint8_t pdu[300];
    uint16_t regs[8];
    /* Positions while live mode is off: stored, not submitted. */
    pack_live(regs, 1, 2, 3, 4, 0, o);
    CHECK(rig_send(&r, pdu, write_pdu(pdu, 110, regs, 7)) == 12);
    CHECK(r.svc.ncalls == 0);
    /* One write switches live mode on and submits the position. */
    pack_live(regs, 10.5, -20.25, 5.125, 6, 1, o);
    rig_send(&r, pdu, write_pdu(pdu, 110, regs, 8));
    CHECK(r.svc.ncalls == 2 && r.svc.calls[0].kind == 'm' && r.svc.calls[0].command == 1);
    CHECK(r.svc.calls[1].kind == 'p' && r.svc.calls[1].xyz[0] == 10.5 && r.svc.calls[1].xyz[1] == -20.25 &&
          r.svc.calls[1].xyz[2] == 5.125 && r.svc.calls[1].tool == 6);
    /* X and Y alone only stage; Z's second word submits. */
    pack_live(regs, 11.5, -21.5, 4.0, 6, 1, o);
    rig_send(&r, pdu, write_pdu(pdu, 110, regs, 4));
    CHECK(r.svc.ncalls == 2);
    rig_send(&r, pdu, write_pdu(pdu, 114, regs + 4, 2));
    CHECK(r.svc.ncalls == 3 && r.svc.calls[2].xyz[0] == 11.5 && r.svc.calls[2].xyz[2] == 4.0);
    /* A NaN axis is refused and reported. */
    uint16_t nan_regs[2] = {0x7FC0, 0x0000};
    if (o == FM_MODBUS_WORDS_CDAB) {
        nan_regs[0] = 0;
        nan_regs[1] = 0x7FC0;
    }
    rig_send(&r, pdu, write_pdu(pdu, 114, nan_regs, 2));
    CHECK(r.svc.ncalls == 3);
    rig_send(&r, pdu, read_pdu(pdu, 0x04, 26, 1));
    CHECK(reg_at(&r, 0) == FM_MODBUS_ERR_LIVE_REFUSED);
    /* Off again: one call; writing off twice: still one. */
    uint8_t off[5] = {0x06, 0, 117, 0, 0};
    rig_send(&r, off, 5);
    rig_send(&r, off, 5);
    CHECK(mt_count_calls(&r.svc, 'm') == 2);
    /* Read back what the controller wrote. */
    rig_send(&r, pdu, read_pdu(pdu, 0x03, 116, 2));
    CHECK(reg_at(&r, 0) == 6 && reg_at(&r, 1) == 0);
    mt_service_destroy(&r.svc);
}

/* Feed an attack stream to the engine as the server would. */
static void check_attack_engine(const mt_attack *a, int commands, int live)
{
    rig r;
    rig_init(&r, commands, live, 0, FM_MODBUS_WORDS_ABCD);
    int total = fm_modbus_frame_length(a->bytes, a->len);
    int ok;
    if (a->expect == MT_EXPECT_CLOSE) {
        ok = total < 0;
    } else if (a->expect == MT_EXPECT_INCOMPLETE) {
        ok = total > 0 && (size_t)total > a->len;
    } else {
        ok = total > 0 && (size_t)total <= a->len;
        if (ok) {
            r.reply_len = fm_modbus_engine_handle(&r.eng, a->bytes, (size_t)total, r.reply);
            ok = r.reply_len == 9 && r.reply[7] == (a->bytes[7] | 0x80) && r.reply[8] == a->code &&
                 memcmp(r.reply, a->bytes, 4) == 0 && r.reply[6] == a->bytes[6];
        }
    }
    if (!ok)
        fprintf(stderr, "attack %s (commands %d, live %d): unexpected outcome\n", a->name, commands, live);
    CHECK(ok);
    /* No attack frame may reach the service's write side. */
    CHECK(mt_count_calls(&r.svc, 'c') == 0 && mt_count_calls(&r.svc, 'p') == 0);
    mt_service_destroy(&r.svc);
}

static void test_attacks(void)
{
    DIR *d = opendir("modbus/attacks");
    CHECK(d != NULL);
    if (!d)
        return;
    int count = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        size_t n = strlen(e->d_name);
        if (n < 5 || strcmp(e->d_name + n - 4, ".hex") != 0)
            continue;
        char path[512];
        snprintf(path, sizeof path, "modbus/attacks/%s", e->d_name);
        mt_attack a;
        int loaded = mt_attack_load(path, e->d_name, &a) == 0;
        if (!loaded)
            fprintf(stderr, "cannot parse %s\n", path);
        CHECK(loaded);
        if (!loaded)
            continue;
        check_attack_engine(&a, 0, 0);
        check_attack_engine(&a, 1, 1);
        count++;
    }
    closedir(d);
    CHECK(count >= 30);
}

/* Random frames with valid headers: every reply is well formed, echoes the
 * header, and is the request's function code or its exception. */
static void test_random_frames(void)
{
    rig r;
    rig_init(&r, 1, 1, 100, FM_MODBUS_WORDS_ABCD);
    uint8_t adu[FM_MODBUS_MAX_ADU];
    for (int iter = 0; iter < 20000; iter++) {
        unsigned pdu_len = 1 + (unsigned)(test_rand01() * 253);
        size_t n = 7 + pdu_len;
        for (size_t i = 0; i < n; i++)
            adu[i] = (uint8_t)(test_rand01() * 256);
        adu[2] = adu[3] = 0;
        adu[4] = 0;
        adu[5] = (uint8_t)(pdu_len + 1);
        /* Bias towards the served codes and the map's addresses. */
        static const uint8_t fcs[] = {3, 4, 6, 16, 23};
        if (test_rand01() < 0.8)
            adu[7] = fcs[(int)(test_rand01() * 5)];
        if (test_rand01() < 0.5 && pdu_len >= 3) {
            adu[8] = 0;
            adu[9] = (uint8_t)(test_rand01() * 120);
        }
        size_t m = fm_modbus_engine_handle(&r.eng, adu, n, r.reply);
        int ok = m >= 9 && m <= FM_MODBUS_MAX_ADU && memcmp(r.reply, adu, 4) == 0 &&
                 (size_t)(((unsigned)r.reply[4] << 8 | r.reply[5]) + 6) == m &&
                 (r.reply[7] == adu[7] || r.reply[7] == (adu[7] | 0x80));
        CHECK(ok);
        if (!ok)
            break;
        fm_modbus_engine_tick(&r.eng, 1000 + iter);
    }
    mt_service_destroy(&r.svc);
}

int main(void)
{
    test_packing();
    test_framing();
    test_status_map(FM_MODBUS_WORDS_ABCD);
    test_status_map(FM_MODBUS_WORDS_CDAB);
    test_heartbeat();
    test_writes_refused();
    test_commands();
    test_watchdog();
    test_live(FM_MODBUS_WORDS_ABCD);
    test_live(FM_MODBUS_WORDS_CDAB);
    test_attacks();
    test_random_frames();
    return test_summary("modbus_unit");
}
