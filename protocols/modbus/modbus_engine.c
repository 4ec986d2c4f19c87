/* modbus_engine.c: the register map (version 1) and the request handler.
 * Every request PDU is parsed and validated here, field by field, against the
 * length the MBAP header announced; nothing is handed to libmodbus's
 * modbus_reply, whose history of out-of-bounds bugs on malformed write
 * requests (CVE-2019-14462/14463, CVE-2022-0367) is what this module must not
 * inherit. Only the writable ranges 100-103 and 110-117 can ever change. */
#include "protocols/modbus/modbus_internal.h"

#include <float.h>
#include <math.h>
#include <string.h>

/* Function codes served. */
#define FC_READ_HOLDING 0x03
#define FC_READ_INPUT 0x04
#define FC_WRITE_SINGLE 0x06
#define FC_WRITE_MULTIPLE 0x10
#define FC_WRITE_AND_READ 0x17

/* Quantity limits from the Modbus application protocol spec (v1.1b3). */
#define MAX_READ_QUANTITY 125
#define MAX_WRITE_QUANTITY 123
#define MAX_WR_WRITE_QUANTITY 121

#define HEARTBEAT_PERIOD_MS 100

void fm_modbus_pack_u32(uint32_t value, fm_modbus_word_order order, uint16_t out[2])
{
    uint16_t high = (uint16_t)(value >> 16), low = (uint16_t)(value & 0xFFFFu);
    if (order == FM_MODBUS_WORDS_CDAB) {
        out[0] = low;
        out[1] = high;
    } else {
        out[0] = high;
        out[1] = low;
    }
}

uint32_t fm_modbus_unpack_u32(const uint16_t in[2], fm_modbus_word_order order)
{
    if (order == FM_MODBUS_WORDS_CDAB)
        return ((uint32_t)in[1] << 16) | in[0];
    return ((uint32_t)in[0] << 16) | in[1];
}

void fm_modbus_pack_f32(double value, fm_modbus_word_order order, uint16_t out[2])
{
    /* Converting a double outside float's range is undefined in C; saturate
     * to infinity, which is what an HMI should show for such a value. */
    float f;
    if (isnan(value))
        f = NAN;
    else if (value > FLT_MAX)
        f = INFINITY;
    else if (value < -FLT_MAX)
        f = -INFINITY;
    else
        f = (float)value;
    uint32_t bits;
    memcpy(&bits, &f, sizeof bits);
    fm_modbus_pack_u32(bits, order, out);
}

float fm_modbus_unpack_f32(const uint16_t in[2], fm_modbus_word_order order)
{
    uint32_t bits = fm_modbus_unpack_u32(in, order);
    float f;
    memcpy(&f, &bits, sizeof f);
    return f;
}

void fm_modbus_engine_init(fm_modbus_engine *e, const fm_modbus_config *cfg,
                           const fm_modbus_service *svc, int64_t now_ms)
{
    memset(e, 0, sizeof *e);
    e->word_order = cfg->word_order == FM_MODBUS_WORDS_CDAB ? FM_MODBUS_WORDS_CDAB
                                                            : FM_MODBUS_WORDS_ABCD;
    e->enable_commands = cfg->enable_commands != 0;
    e->enable_live = cfg->enable_live != 0;
    e->watchdog_ms = cfg->watchdog_ms > 0 ? cfg->watchdog_ms : 0;
    if (svc)
        e->svc = *svc;
    e->now_ms = now_ms;
    e->next_heartbeat_ms = now_ms + HEARTBEAT_PERIOD_MS;
}

int fm_modbus_engine_tick(fm_modbus_engine *e, int64_t now_ms)
{
    e->now_ms = now_ms;
    /* A stalled loop (debugger, suspended VM) catches up at most a minute of
     * ticks and then resynchronises, rather than looping for hours. */
    if (now_ms - e->next_heartbeat_ms > 60000)
        e->next_heartbeat_ms = now_ms;
    while (now_ms >= e->next_heartbeat_ms) {
        e->heartbeat++;
        e->next_heartbeat_ms += HEARTBEAT_PERIOD_MS;
    }
    if (e->watchdog_ms > 0 && e->watchdog_armed && !e->watchdog_fired &&
        now_ms - e->watchdog_changed_ms >= e->watchdog_ms) {
        e->watchdog_fired = 1;
        e->last_error = FM_MODBUS_ERR_WATCHDOG;
        if (e->svc.watchdog_expired)
            e->svc.watchdog_expired(e->svc.ctx);
    }
    return (int)(e->next_heartbeat_ms - now_ms);
}

void fm_modbus_status_registers(fm_modbus_engine *e, const fm_modbus_status *s,
                                uint16_t regs[FM_MODBUS_STATUS_COUNT])
{
    fm_modbus_word_order o = e->word_order;
    /* The job's error shows when it changes; a later command result or
     * watchdog expiry may overwrite it (register 26 is the latest event). */
    if (s->last_error != e->svc_error_seen) {
        e->svc_error_seen = s->last_error;
        if (s->last_error != 0)
            e->last_error = s->last_error;
    }
    regs[0] = FM_MODBUS_MAP_VERSION;
    regs[1] = s->bits;
    regs[2] = e->heartbeat;
    fm_modbus_pack_u32(s->block, o, &regs[3]);
    fm_modbus_pack_u32(s->source_line, o, &regs[5]);
    regs[7] = s->progress_permille;
    regs[8] = s->tool;
    fm_modbus_pack_f32(s->tool_tip[0], o, &regs[9]);
    fm_modbus_pack_f32(s->tool_tip[1], o, &regs[11]);
    fm_modbus_pack_f32(s->tool_tip[2], o, &regs[13]);
    fm_modbus_pack_f32(s->program_time_s, o, &regs[15]);
    fm_modbus_pack_f32(s->removed_mm3, o, &regs[17]);
    fm_modbus_pack_f32(s->remaining_mm3, o, &regs[19]);
    fm_modbus_pack_f32(s->removal_rate_mm3_s, o, &regs[21]);
    regs[23] = s->finding_count;
    fm_modbus_pack_u32(s->first_finding_line, o, &regs[24]);
    regs[26] = e->last_error;
    regs[27] = s->selected_slot;
    regs[28] = e->ack_seq;
}

int fm_modbus_frame_length(const uint8_t *buf, size_t have)
{
    if (have < FM_MODBUS_MBAP_LEN)
        return 0;
    unsigned protocol = ((unsigned)buf[2] << 8) | buf[3];
    unsigned length = ((unsigned)buf[4] << 8) | buf[5];
    /* Validated before a single byte of the body is read: the buffer is the
     * full 260 bytes, and the length field alone decides where a frame ends. */
    if (protocol != 0 || length < 2 || length > FM_MODBUS_MAX_LENGTH_FIELD)
        return -1;
    return 6 + (int)length;
}

static unsigned get16(const uint8_t *p)
{
    return ((unsigned)p[0] << 8) | p[1];
}

/* Where a register range lives. Ranges never straddle two blocks. */
enum block { BLOCK_NONE, BLOCK_STATUS, BLOCK_CMD, BLOCK_LIVE };

static enum block find_block(unsigned start, unsigned count, unsigned base, unsigned n, enum block b)
{
    /* start and count are at most 0xFFFF and 125: no overflow in unsigned. */
    if (start >= base && start + count <= base + n)
        return b;
    return BLOCK_NONE;
}

static enum block read_block(unsigned fc, unsigned start, unsigned count)
{
    enum block b = find_block(start, count, 0, FM_MODBUS_STATUS_COUNT, BLOCK_STATUS);
    if (b != BLOCK_NONE || fc == FC_READ_INPUT)
        return b;
    b = find_block(start, count, FM_MODBUS_CMD_BASE, FM_MODBUS_CMD_COUNT, BLOCK_CMD);
    if (b != BLOCK_NONE)
        return b;
    return find_block(start, count, FM_MODBUS_LIVE_BASE, FM_MODBUS_LIVE_COUNT, BLOCK_LIVE);
}

static enum block write_block(const fm_modbus_engine *e, unsigned start, unsigned count)
{
    if (e->enable_commands &&
        find_block(start, count, FM_MODBUS_CMD_BASE, FM_MODBUS_CMD_COUNT, BLOCK_CMD) != BLOCK_NONE)
        return BLOCK_CMD;
    if (e->enable_live &&
        find_block(start, count, FM_MODBUS_LIVE_BASE, FM_MODBUS_LIVE_COUNT, BLOCK_LIVE) != BLOCK_NONE)
        return BLOCK_LIVE;
    return BLOCK_NONE;
}

/* Reply helpers. r points at the reply ADU; the PDU starts at r + 7. */
static size_t finish(uint8_t *r, const uint8_t *req, size_t pdu_len)
{
    memcpy(r, req, 4); /* transaction id, protocol id */
    unsigned length = (unsigned)pdu_len + 1;
    r[4] = (uint8_t)(length >> 8);
    r[5] = (uint8_t)length;
    r[6] = req[6]; /* unit id echoed */
    return FM_MODBUS_MBAP_LEN + pdu_len;
}

static size_t exception(uint8_t *r, const uint8_t *req, unsigned fc, unsigned code)
{
    r[7] = (uint8_t)(fc | 0x80u);
    r[8] = (uint8_t)code;
    return finish(r, req, 2);
}

/* Copy count registers starting at start (already validated) into out. */
static void read_registers(fm_modbus_engine *e, enum block b, unsigned start, unsigned count,
                           uint8_t *out)
{
    uint16_t regs[FM_MODBUS_STATUS_COUNT];
    const uint16_t *src;
    unsigned base;
    if (b == BLOCK_STATUS) {
        fm_modbus_status s;
        memset(&s, 0, sizeof s);
        if (e->svc.read_status)
            e->svc.read_status(e->svc.ctx, &s);
        fm_modbus_status_registers(e, &s, regs);
        src = regs;
        base = 0;
    } else if (b == BLOCK_CMD) {
        src = e->cmd_regs;
        base = FM_MODBUS_CMD_BASE;
    } else {
        src = e->live_regs;
        base = FM_MODBUS_LIVE_BASE;
    }
    for (unsigned i = 0; i < count; i++) {
        uint16_t v = src[start - base + i];
        out[2 * i] = (uint8_t)(v >> 8);
        out[2 * i + 1] = (uint8_t)v;
    }
}

uint16_t fm_modbus_error_code(const fm_error *err, int live)
{
    static const struct {
        const char *reason;
        uint16_t code;
    } codes[] = {{"unknown_command", FM_MODBUS_ERR_UNKNOWN_COMMAND},
                 {"no_job", FM_MODBUS_ERR_NO_JOB},
                 {"not_found", FM_MODBUS_ERR_NO_JOB},
                 {"bad_slot", FM_MODBUS_ERR_BAD_SLOT},
                 {"bad_state", FM_MODBUS_ERR_BAD_STATE},
                 {"busy", FM_MODBUS_ERR_BUSY}};
    for (size_t i = 0; i < sizeof codes / sizeof codes[0]; i++)
        if (!strcmp(err->reason, codes[i].reason)) return codes[i].code;
    if (live) return FM_MODBUS_ERR_LIVE_REFUSED;
    return err->code >= FM_ERR_INPUT && err->code <= FM_ERR_INTERNAL ? (uint16_t)err->code
                                                                      : FM_MODBUS_ERR_JOB_INTERNAL;
}

static void run_command(fm_modbus_engine *e, uint16_t seq)
{
    uint16_t code = FM_MODBUS_ERR_UNKNOWN_COMMAND;
    int cmd = e->cmd_regs[0];
    if (cmd >= FM_MODBUS_CMD_START && cmd <= FM_MODBUS_CMD_SELECT && e->svc.command) {
        fm_error err;
        fm_error_clear(&err);
        code = e->svc.command(e->svc.ctx, cmd, e->cmd_regs[2], &err) == FM_OK
                   ? FM_MODBUS_ERR_NONE
                   : fm_modbus_error_code(&err, 0);
    }
    /* Acknowledged whatever the outcome: the HMI learns the result from 26. */
    e->ack_seq = seq;
    e->last_error = code;
}

/* Apply a validated write of count values (big-endian pairs at data) to
 * block b, then act on it: new sequence number, watchdog, live mode. */
static void write_registers(fm_modbus_engine *e, enum block b, unsigned start, unsigned count,
                            const uint8_t *data)
{
    if (b == BLOCK_CMD) {
        unsigned first = start - FM_MODBUS_CMD_BASE;
        int seq_written = 0, watchdog_written = 0;
        uint16_t old_watchdog = e->cmd_regs[3];
        for (unsigned i = 0; i < count; i++) {
            unsigned idx = first + i;
            e->cmd_regs[idx] = (uint16_t)get16(data + 2 * i);
            seq_written |= idx == 1;
            watchdog_written |= idx == 3;
        }
        if (watchdog_written) {
            /* The first write arms the watchdog, so an HMI that never uses it
             * never pauses anything. */
            if (!e->watchdog_armed || e->cmd_regs[3] != old_watchdog) {
                e->watchdog_armed = 1;
                e->watchdog_fired = 0;
                e->watchdog_changed_ms = e->now_ms;
            }
        }
        if (seq_written && e->cmd_regs[1] != e->ack_seq)
            run_command(e, e->cmd_regs[1]);
        return;
    }
    unsigned first = start - FM_MODBUS_LIVE_BASE;
    int position_written = 0, mode_written = 0;
    for (unsigned i = 0; i < count; i++) {
        unsigned idx = first + i;
        e->live_regs[idx] = (uint16_t)get16(data + 2 * i);
        position_written |= idx == 5 || idx == 6; /* Z's second word or the tool */
        mode_written |= idx == 7;
    }
    if (mode_written) {
        int on = e->live_regs[7] != 0;
        if (on != e->live_on) {
            fm_error err;
            fm_error_clear(&err);
            if (e->svc.live_mode && e->svc.live_mode(e->svc.ctx, on, &err) == FM_OK)
                e->live_on = on;
            else
                e->last_error = fm_modbus_error_code(&err, 1);
        }
    }
    if (position_written && e->live_on) {
        double xyz[3];
        for (int k = 0; k < 3; k++)
            xyz[k] = fm_modbus_unpack_f32(&e->live_regs[2 * k], e->word_order);
        fm_error err;
        fm_error_clear(&err);
        /* A NaN or infinite axis is never a motion. */
        if (!(isfinite(xyz[0]) && isfinite(xyz[1]) && isfinite(xyz[2]) && e->svc.live_position))
            e->last_error = FM_MODBUS_ERR_LIVE_REFUSED;
        else if (e->svc.live_position(e->svc.ctx, xyz, e->live_regs[6], &err) != FM_OK)
            e->last_error = fm_modbus_error_code(&err, 1);
    }
}

size_t fm_modbus_engine_handle(fm_modbus_engine *e, const uint8_t *adu, size_t len,
                               uint8_t reply[FM_MODBUS_MAX_ADU])
{
    int expect = fm_modbus_frame_length(adu, len);
    if (expect <= 0 || (size_t)expect != len)
        return 0;
    const uint8_t *pdu = adu + FM_MODBUS_MBAP_LEN;
    size_t pdu_len = len - FM_MODBUS_MBAP_LEN; /* >= 1: length field >= 2 */
    unsigned fc = pdu[0];

    switch (fc) {
    case FC_READ_HOLDING:
    case FC_READ_INPUT: {
        if (pdu_len != 5)
            return exception(reply, adu, fc, FM_MODBUS_EX_ILLEGAL_VALUE);
        unsigned start = get16(pdu + 1), count = get16(pdu + 3);
        if (count < 1 || count > MAX_READ_QUANTITY)
            return exception(reply, adu, fc, FM_MODBUS_EX_ILLEGAL_VALUE);
        enum block b = read_block(fc, start, count);
        if (b == BLOCK_NONE)
            return exception(reply, adu, fc, FM_MODBUS_EX_ILLEGAL_ADDRESS);
        reply[7] = (uint8_t)fc;
        reply[8] = (uint8_t)(2 * count);
        read_registers(e, b, start, count, reply + 9);
        return finish(reply, adu, 2 + 2 * count);
    }
    case FC_WRITE_SINGLE: {
        if (pdu_len != 5)
            return exception(reply, adu, fc, FM_MODBUS_EX_ILLEGAL_VALUE);
        unsigned addr = get16(pdu + 1);
        enum block b = write_block(e, addr, 1);
        if (b == BLOCK_NONE)
            return exception(reply, adu, fc, FM_MODBUS_EX_ILLEGAL_ADDRESS);
        write_registers(e, b, addr, 1, pdu + 3);
        memcpy(reply + 7, pdu, 5); /* the reply echoes the request */
        return finish(reply, adu, 5);
    }
    case FC_WRITE_MULTIPLE: {
        if (pdu_len < 6)
            return exception(reply, adu, fc, FM_MODBUS_EX_ILLEGAL_VALUE);
        unsigned start = get16(pdu + 1), count = get16(pdu + 3), bytes = pdu[5];
        /* The byte count must match the quantity and the frame (the check
         * whose absence was CVE-2019-14462). */
        if (count < 1 || count > MAX_WRITE_QUANTITY || bytes != 2 * count || pdu_len != 6 + bytes)
            return exception(reply, adu, fc, FM_MODBUS_EX_ILLEGAL_VALUE);
        enum block b = write_block(e, start, count);
        if (b == BLOCK_NONE)
            return exception(reply, adu, fc, FM_MODBUS_EX_ILLEGAL_ADDRESS);
        write_registers(e, b, start, count, pdu + 6);
        memcpy(reply + 7, pdu, 5);
        return finish(reply, adu, 5);
    }
    case FC_WRITE_AND_READ: {
        if (pdu_len < 10)
            return exception(reply, adu, fc, FM_MODBUS_EX_ILLEGAL_VALUE);
        unsigned rstart = get16(pdu + 1), rcount = get16(pdu + 3);
        unsigned wstart = get16(pdu + 5), wcount = get16(pdu + 7), bytes = pdu[9];
        if (rcount < 1 || rcount > MAX_READ_QUANTITY || wcount < 1 ||
            wcount > MAX_WR_WRITE_QUANTITY || bytes != 2 * wcount || pdu_len != 10 + bytes)
            return exception(reply, adu, fc, FM_MODBUS_EX_ILLEGAL_VALUE);
        /* Both ranges are checked before anything is written (CVE-2022-0367
         * was a write through an unchecked address). */
        enum block wb = write_block(e, wstart, wcount);
        enum block rb = read_block(FC_READ_HOLDING, rstart, rcount);
        if (wb == BLOCK_NONE || rb == BLOCK_NONE)
            return exception(reply, adu, fc, FM_MODBUS_EX_ILLEGAL_ADDRESS);
        write_registers(e, wb, wstart, wcount, pdu + 10);
        reply[7] = (uint8_t)fc;
        reply[8] = (uint8_t)(2 * rcount);
        read_registers(e, rb, rstart, rcount, reply + 9);
        return finish(reply, adu, 2 + 2 * rcount);
    }
    default:
        /* Coils, discrete inputs, diagnostics, file records, identification,
         * and any code >= 0x80 (which is not a request at all). */
        return exception(reply, adu, fc & 0x7Fu, FM_MODBUS_EX_ILLEGAL_FUNCTION);
    }
}
