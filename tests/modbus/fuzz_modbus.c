/* fuzz_modbus.c: libFuzzer target over the request path with no sockets: the
 * input is a byte stream as a client would send it; it is framed exactly as
 * the server frames it and every complete frame goes through the engine
 * (commands, live mode and watchdog on, so the write paths are reached).
 * The reply must always be a well-formed ADU for the same transaction. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "protocols/modbus/modbus_internal.h"

static void fz_read_status(void *ctx, fm_modbus_status *out)
{
    (void)ctx;
    memset(out, 0, sizeof *out);
    out->block = 42;
    out->tool_tip[0] = 1.5;
    out->removed_mm3 = 1e40; /* beyond float: saturates */
}
/* Refusals of every kind the register map knows, picked by the input. */
static const char *const fz_reasons[] = {"", "unknown_command", "no_job", "bad_slot",
                                         "bad_state", "busy", "something_else"};
static fm_status fz_command(void *ctx, int command, uint32_t argument, fm_error *err)
{
    (void)ctx;
    unsigned pick = ((unsigned)command + argument) % 8;
    if (pick == 7) return FM_OK;
    return fm_error_set_reason(err, (fm_status)(2 + pick % 4), fz_reasons[pick % 7], "refused");
}
static fm_status fz_live_position(void *ctx, const double xyz[3], int tool, fm_error *err)
{
    (void)ctx;
    if (xyz[0] > 1e6) return fm_error_set_reason(err, FM_ERR_LIMIT, "busy", "busy");
    if (tool > 1000) return fm_error_set(err, FM_ERR_INPUT, "refused");
    return FM_OK;
}
static fm_status fz_live_mode(void *ctx, int on, fm_error *err)
{
    (void)ctx;
    (void)on;
    (void)err;
    return FM_OK;
}
static void fz_watchdog(void *ctx)
{
    (void)ctx;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fm_modbus_config cfg;
    fm_modbus_config_default(&cfg);
    cfg.enable_commands = 1;
    cfg.enable_live = 1;
    cfg.watchdog_ms = 50;
    cfg.word_order = size > 0 && (data[0] & 1) ? FM_MODBUS_WORDS_CDAB : FM_MODBUS_WORDS_ABCD;
    fm_modbus_service svc = {NULL, fz_read_status, fz_command, fz_live_position, fz_live_mode, fz_watchdog};
    fm_modbus_engine e;
    fm_modbus_engine_init(&e, &cfg, &svc, 0);

    /* The server's own framing: a 260-byte buffer filled from the stream. */
    uint8_t rx[FM_MODBUS_MAX_ADU];
    uint8_t reply[FM_MODBUS_MAX_ADU];
    size_t rx_len = 0, off = 0;
    int64_t now = 0;
    while (off < size) {
        size_t take = size - off < sizeof rx - rx_len ? size - off : sizeof rx - rx_len;
        memcpy(rx + rx_len, data + off, take);
        rx_len += take;
        off += take;
        for (;;) {
            int total = fm_modbus_frame_length(rx, rx_len);
            if (total < 0)
                return 0; /* the server closes the connection */
            if (total == 0 || rx_len < (size_t)total)
                break;
            size_t n = fm_modbus_engine_handle(&e, rx, (size_t)total, reply);
            if (n < 9 || n > FM_MODBUS_MAX_ADU || memcmp(reply, rx, 4) != 0 ||
                (size_t)(((unsigned)reply[4] << 8 | reply[5]) + 6) != n ||
                (reply[7] & 0x7F) != (rx[7] & 0x7F))
                abort();
            rx_len -= (size_t)total;
            memmove(rx, rx + total, rx_len);
            now += 37;
            fm_modbus_engine_tick(&e, now);
        }
        if (rx_len == sizeof rx)
            abort(); /* a full buffer always holds a complete frame */
    }
    return 0;
}
