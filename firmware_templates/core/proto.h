/* proto.h - the link protocol runtime: frame assembly, pack/unpack, error counters.
 *
 * Wire format (see docs/ARCHITECTURE.md "Link protocol"):
 *     COBS( msg_id:u8 | payload | crc16:u16-le ) 0x00
 * CRC-16/CCITT-FALSE over msg_id + payload; payload fields little-endian, packed; a variable
 * array is preceded by its u8 count. At most PROTO_MAX_FRAME (64) bytes before COBS.
 *
 * The messages are defined once, in proleg/protocol/definition.py. proleg.protocol.render
 * turns them into proto_gen.h (ids, enums, one struct per message, the proto_msg_t union)
 * and proto_gen.c (field descriptor tables). This file and proto.c are hand-written and the
 * same for every robot: they interpret those tables. C99, no malloc, no recursion.
 *
 * Usage (firmware):
 *     static proto_rx_t rx;  static proto_msg_t m;  static uint8_t tx[PROTO_MAX_ENCODED];
 *     proto_rx_init(&rx);
 *     int c = uart_read_byte();
 *     if (c >= 0 && proto_rx_byte(&rx, (uint8_t)c, &m)) {
 *         switch (m.id) { case PROTO_ID_START: ... m.u.start.gait ... }
 *     } else if (rx.rej_error) {               // CRC-valid frame refused: NACK it
 *         nack(rx.rej_token, rx.rej_id, rx.rej_error);
 *     }
 *     m.id = PROTO_ID_ACK; m.u.ack.token = t; m.u.ack.cmd = id;
 *     size_t n = proto_encode(&m, tx, sizeof tx);   // n == 0: does not fit / invalid message
 *     uart_write(tx, (uint16_t)n);
 * Every command struct starts with its token: PROTO_CMD_TOKEN(&m) reads it for any command.
 * STATS: rx.count supplies rx_ok..bad_value; nacks, tx_frames, tx_dropped are counted by tx.c.
 * RAM: proto_rx_t ~ 96 B; proto_msg_t is its largest member (LOAD_GAIT, ~52 B).
 *
 * Flash tables: on AVR the descriptor tables live in flash (PROGMEM) and are read with
 * pgm_read_byte; elsewhere plain const. Override PROTO_CONST / PROTO_READ_BYTE if needed.
 */
#ifndef PROLEG_PROTO_H
#define PROLEG_PROTO_H

#include <stddef.h>
#include <stdint.h>

#if defined(__AVR__) && !defined(PROTO_CONST)
#include <avr/pgmspace.h>
#define PROTO_CONST const PROGMEM
#define PROTO_READ_BYTE(p) pgm_read_byte(p)
#endif
#ifndef PROTO_CONST
#define PROTO_CONST const
#endif
#ifndef PROTO_READ_BYTE
#define PROTO_READ_BYTE(p) (*(const uint8_t *)(p))
#endif

/* PROTO_PACKED_LAYOUT: structs without padding, little-endian (AVR): a message's struct is
 * its wire bytes with each array at its capacity, and proto_gen.c's tables are per-message
 * byte strings (proto_layouts) instead of per-field descriptors. A host test may set it
 * (proto_gen.h then packs the structs). */
#if defined(__AVR__) && !defined(PROTO_PACKED_LAYOUT)
#define PROTO_PACKED_LAYOUT 1
#endif
#ifndef PROTO_PACKED_LAYOUT
#define PROTO_PACKED_LAYOUT 0
#endif

#include "cobs.h"
#include "proto_gen.h" /* PROTO_ID_*, PROTO_ERR_* ..., proto_<msg>_t, proto_msg_t */

/* ---- descriptor tables (rendered into proto_gen.c, interpreted by proto.c) ---- */
enum { /* proto_field_t.type: low nibble = element type, PROTO_F_ARRAY = u8 count first */
    PROTO_T_U8 = 0, PROTO_T_U16 = 1, PROTO_T_U32 = 2, PROTO_T_I16 = 3, PROTO_T_I32 = 4,
    PROTO_T_CHAR = 5, /* fixed-length text: max = length in bytes */
    PROTO_F_ARRAY = 0x80
};
typedef struct {
    uint8_t type;         /* PROTO_T_* | PROTO_F_ARRAY */
    uint8_t offset;       /* offsetof(struct, field) */
    uint8_t max;          /* array capacity / text length; 0 for scalars */
    uint8_t count_offset; /* arrays: offsetof(struct, <field>_count); else 0 */
} proto_field_t;
typedef struct {
    uint8_t id;    /* PROTO_ID_* */
    uint8_t first; /* index of the first field in proto_fields */
    uint8_t n;     /* number of fields */
} proto_msgdesc_t;
#if PROTO_PACKED_LAYOUT
enum { PROTO_L_ARRAY = 0x80 }; /* proto_layouts: 1..127 = bytes as is; ARRAY | size, capacity */
typedef struct {
    uint8_t id;    /* PROTO_ID_* */
    uint8_t first; /* index of its 0-terminated layout in proto_layouts */
} proto_msglayout_t;
extern PROTO_CONST uint8_t proto_layouts[];
extern PROTO_CONST proto_msglayout_t proto_messages[PROTO_N_MESSAGES];
#else
extern PROTO_CONST proto_field_t proto_fields[];
extern PROTO_CONST proto_msgdesc_t proto_messages[PROTO_N_MESSAGES];
#endif

/* ---- receiving ---- */
typedef struct {
    uint32_t frames_ok;      /* valid frames decoded */
    uint32_t crc_errors;     /* COBS ok, CRC wrong */
    uint32_t framing_errors; /* bad COBS, shorter than id+crc, longer than PROTO_MAX_FRAME */
    uint32_t unknown_ids;    /* CRC ok, id not in the table */
    uint32_t bad_length;     /* CRC ok, payload length does not match the layout */
    uint32_t bad_value;      /* CRC ok, array count above this build's maximum */
} proto_counters_t;

typedef struct proto_rx {
    uint8_t buf[PROTO_MAX_FRAME]; /* decoded bytes of the frame being received */
    uint8_t len;                  /* bytes in buf */
    cobs_dec_t cobs;              /* incremental COBS decoder state */
    uint8_t overflow;             /* frame longer than PROTO_MAX_FRAME: drop at delimiter */
    /* Set on the byte that ended a CRC-valid but refused frame, cleared by the next call:
     * rej_error = PROTO_ERR_UNKNOWN_MESSAGE / _BAD_LENGTH / _TOO_LONG, rej_id = its msg_id,
     * rej_token = its first payload byte (0 if none). 0 = nothing refused. */
    uint8_t rej_error, rej_id, rej_token;
    proto_counters_t count;
} proto_rx_t;

/* Reset the assembler and zero the counters. The receiver starts "inside a frame": bytes
 * before the first 0x00 are a (counted) broken frame, so a host may send 0x00 first. */
void proto_rx_init(proto_rx_t *rx);

/* Feed one received byte. Returns 1 when this byte (a 0x00) completes a valid frame; *msg
 * then holds it. Otherwise returns 0 (*msg may have been overwritten). Empty frames
 * (0x00 0x00) are ignored. Every broken frame increments exactly one counter. */
int proto_rx_byte(proto_rx_t *rx, uint8_t byte, proto_msg_t *msg);

/* ---- sending ---- */
/* Encode *msg as a complete wire frame (COBS, trailing 0x00) into out. Returns its length
 * (at most PROTO_MAX_ENCODED), or 0 if the id is unknown, an array count exceeds the
 * build's maximum, or cap is too small. Text fields are copied as is (keep them NUL-padded). */
size_t proto_encode(const proto_msg_t *msg, uint8_t *out, size_t cap);

/* ---- below the framing (for other transports and tests) ---- */
/* Pack msg_id + payload (no CRC, no COBS) into out; returns length or 0 as proto_encode. */
size_t proto_pack(const proto_msg_t *msg, uint8_t *out, size_t cap);
/* Unpack msg_id + payload (no CRC) of n bytes into *msg. Returns 0 on success, else
 * PROTO_ERR_UNKNOWN_MESSAGE, PROTO_ERR_BAD_LENGTH or PROTO_ERR_TOO_LONG (array count). */
uint8_t proto_unpack(const uint8_t *frame, size_t n, proto_msg_t *msg);

/* Token of a command (every host->robot struct starts with uint8_t token). */
#define PROTO_CMD_TOKEN(m) (((const uint8_t *)&(m)->u)[0])

#endif /* PROLEG_PROTO_H */
