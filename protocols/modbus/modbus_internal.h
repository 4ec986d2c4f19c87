/* modbus_internal.h: the parts of the Modbus module below the socket layer,
 * shared by the server, its unit tests and the fuzz target (private to
 * protocols/modbus and tests/modbus). The engine turns one complete request
 * ADU into one reply ADU with no I/O, so it can be tested frame by frame. */
#ifndef FM_MODBUS_INTERNAL_H
#define FM_MODBUS_INTERNAL_H

#include <stddef.h>
#include <stdint.h>

#include "protocols/modbus/modbus_server.h"

/* Modbus/TCP: 7-byte MBAP header (transaction, protocol, length, unit) and a
 * PDU of at most 253 bytes. The length field counts the unit id and the PDU. */
#define FM_MODBUS_MBAP_LEN 7
#define FM_MODBUS_MAX_ADU 260
#define FM_MODBUS_MAX_LENGTH_FIELD 254

/* The register map, version 1 (docs/modbus.md). */
#define FM_MODBUS_STATUS_COUNT 29 /* addresses 0..28, FC04 and FC03 */
#define FM_MODBUS_CMD_BASE 100    /* 100..103 */
#define FM_MODBUS_CMD_COUNT 4
#define FM_MODBUS_LIVE_BASE 110   /* 110..117 */
#define FM_MODBUS_LIVE_COUNT 8

/* Standard exception codes. */
#define FM_MODBUS_EX_ILLEGAL_FUNCTION 0x01
#define FM_MODBUS_EX_ILLEGAL_ADDRESS 0x02
#define FM_MODBUS_EX_ILLEGAL_VALUE 0x03

typedef struct fm_modbus_engine {
    fm_modbus_word_order word_order;
    int enable_commands;
    int enable_live;
    int watchdog_ms;
    fm_modbus_service svc;

    uint16_t heartbeat;
    int64_t next_heartbeat_ms;

    uint16_t ack_seq;         /* register 28 */
    uint16_t last_error;      /* register 26 */
    uint16_t svc_error_seen;  /* the service's last_error when last read */
    uint16_t cmd_regs[FM_MODBUS_CMD_COUNT];
    uint16_t live_regs[FM_MODBUS_LIVE_COUNT];
    int live_on;              /* what live_mode() was last told */

    int watchdog_armed;       /* the HMI has written 103 at least once */
    int watchdog_fired;
    int64_t watchdog_changed_ms;
    int64_t now_ms;
} fm_modbus_engine;

/* cfg supplies word order, enables and watchdog; now_ms is any monotonic
 * clock in milliseconds. */
void fm_modbus_engine_init(fm_modbus_engine *e, const fm_modbus_config *cfg,
                           const fm_modbus_service *svc, int64_t now_ms);

/* Advance the clock: heartbeat every 100 ms, HMI watchdog expiry. Returns the
 * milliseconds until the next heartbeat (how long the caller may sleep). */
int fm_modbus_engine_tick(fm_modbus_engine *e, int64_t now_ms);

/* Framing of a byte stream: the total ADU length once the header is in
 * (have >= 7), 0 when more header bytes are needed, -1 when the header is not
 * Modbus/TCP (protocol id not 0, length field outside 2..254): the stream
 * cannot be resynchronised and the connection must close. */
int fm_modbus_frame_length(const uint8_t *buf, size_t have);

/* One complete ADU (len == fm_modbus_frame_length(adu, len)) -> the reply in
 * reply[FM_MODBUS_MAX_ADU]. Returns the reply length, or 0 when the frame is
 * not valid Modbus/TCP and the connection should be closed. */
size_t fm_modbus_engine_handle(fm_modbus_engine *e, const uint8_t *adu, size_t len,
                               uint8_t reply[FM_MODBUS_MAX_ADU]);

/* 32-bit values over two registers in the configured word order. The bytes
 * inside a register are always big-endian (the Modbus rule). */
void fm_modbus_pack_u32(uint32_t value, fm_modbus_word_order order, uint16_t out[2]);
uint32_t fm_modbus_unpack_u32(const uint16_t in[2], fm_modbus_word_order order);
void fm_modbus_pack_f32(double value, fm_modbus_word_order order, uint16_t out[2]);
float fm_modbus_unpack_f32(const uint16_t in[2], fm_modbus_word_order order);

/* The status registers 0..28 for a snapshot (also folds the service's error
 * into register 26). */
void fm_modbus_status_registers(fm_modbus_engine *e, const fm_modbus_status *s,
                                uint16_t regs[FM_MODBUS_STATUS_COUNT]);

#endif
