/* canlink.c - see canlink.h. */
#include "canlink.h"

#include <string.h>

#include "cobs.h"
#include "crc16.h"
#include "hal.h"
#include "robot_config.h"
#include "uart.h"

#if (CFG_CAN_TX_FRAMES & (CFG_CAN_TX_FRAMES - 1u)) || CFG_CAN_TX_FRAMES > 128u
#error "the CAN transmit queue must be a power of two of at most 128 frames"
#endif

#define TXQ_MASK ((uint8_t)(CFG_CAN_TX_FRAMES - 1u))
#define SEG_DATA 7u
#define SEG_LAST 0x80u
#define SLOT_TEL_A 2u
#define SLOT_TEL_B 3u
#define SLOT_PSI 4u
#define SLOT_DUTY 6u

static can_frame_t txq[CFG_CAN_TX_FRAMES];
static volatile uint8_t tx_head, tx_tail; /* frames in (main loop) / out (interrupt), wrapping */
static uint8_t raw[PROTO_MAX_FRAME];      /* msg_id | payload | crc of a message being sent */

/* Receive assembly (interrupt context only): seg[0] is room for the COBS code byte. */
static uint8_t seg[PROTO_MAX_FRAME + 1u];
static uint8_t seg_len, seg_next, seg_bad;

void canlink_init(void)
{
    tx_head = 0;
    tx_tail = 0;
    seg_len = 0;
    seg_next = 0;
    seg_bad = 0;
    hal_can_init();
}

static void put16(uint8_t *d, uint16_t v)
{
    d[0] = (uint8_t)v;
    d[1] = (uint8_t)(v >> 8);
}

static void put32(uint8_t *d, uint32_t v)
{
    put16(d, (uint16_t)v);
    put16(d + 2, (uint16_t)(v >> 16));
}

/* The k-th frame after the queue's head, zeroed, with its identifier. */
static uint8_t *frame(uint8_t k, uint8_t slot)
{
    can_frame_t *f = &txq[(uint8_t)(tx_head + k) & TXQ_MASK];
    f->id = CANLINK_ID(slot);
    f->dlc = 8u;
    memset(f->data, 0, sizeof f->data);
    return f->data;
}

static uint8_t room(void)
{
    return (uint8_t)(CFG_CAN_TX_FRAMES - (uint8_t)(tx_head - tx_tail));
}

/* Four 16-bit elements of an array, from `first` on, zero past `count`. */
static void array4(uint8_t *d, const uint16_t *values, uint8_t count, uint8_t first)
{
    uint8_t i;
    for (i = 0; i < 4u && (uint8_t)(first + i) < count; i++) {
        put16(d + 2u * i, values[first + i]);
    }
}

static uint8_t telemetry(const proto_telemetry_t *t)
{
    uint8_t np = (uint8_t)((t->psi_count + 3u) / 4u), nd = (uint8_t)((t->duty_count + 3u) / 4u);
    uint8_t n = (uint8_t)(2u + np + nd), k, *d;
    if (n > room()) {
        return 0;
    }
    d = frame(0, SLOT_TEL_A);
    put16(d, t->seq);
    put32(d + 2, t->time_ms);
    put16(d + 6, t->measured);
    d = frame(1, SLOT_TEL_B);
    put16(d, t->target);
    d[2] = t->gait;
    d[3] = t->direction;
    d[4] = t->step;
    put16(d + 5, t->flags);
    d[7] = (uint8_t)((t->psi_count & 0x0Fu) | (uint8_t)(t->duty_count << 4));
    for (k = 0; k < np; k++) {
        array4(frame((uint8_t)(2u + k), (uint8_t)(SLOT_PSI + k)), (const uint16_t *)t->psi, t->psi_count,
               (uint8_t)(4u * k));
    }
    for (k = 0; k < nd; k++) {
        array4(frame((uint8_t)(2u + np + k), (uint8_t)(SLOT_DUTY + k)), t->duty, t->duty_count, (uint8_t)(4u * k));
    }
    return n;
}

static uint8_t event(const proto_event_t *e)
{
    uint8_t *d;
    if (room() < 1u) {
        return 0;
    }
    d = frame(0, CANLINK_SLOT_EVENT);
    put32(d, e->time_ms);
    d[4] = e->kind;
    d[5] = e->code;
    put16(d + 6, e->detail);
    return 1;
}

static uint8_t segmented(const proto_msg_t *m)
{
    size_t len = proto_pack(m, raw, sizeof raw - 2u);
    uint16_t crc;
    uint8_t n, k, size, *d;
    if (len == 0u) {
        return 0;
    }
    crc = crc16_ccitt(CRC16_INIT, raw, len);
    put16(raw + len, crc);
    len += 2u;
    n = (uint8_t)((len + SEG_DATA - 1u) / SEG_DATA);
    if (n > room()) {
        return 0;
    }
    for (k = 0; k < n; k++) {
        size = (uint8_t)(len - SEG_DATA * k < SEG_DATA ? len - SEG_DATA * k : SEG_DATA);
        d = frame(k, CANLINK_SLOT_REPLY);
        d[0] = (uint8_t)(k | (uint8_t)((size - 1u) << 4) | (k + 1u == n ? SEG_LAST : 0u));
        memcpy(d + 1, raw + SEG_DATA * k, size);
    }
    return n;
}

uint8_t canlink_send(const proto_msg_t *m)
{
    uint8_t n;
    if (m->id == PROTO_ID_TELEMETRY) {
        n = telemetry(&m->u.telemetry);
    } else if (m->id == PROTO_ID_EVENT) {
        n = event(&m->u.event);
    } else {
        n = segmented(m);
    }
    if (n == 0u) {
        return 0;
    }
    tx_head = (uint8_t)(tx_head + n); /* publish: the frames are complete */
    hal_can_tx_start();
    return 1;
}

int8_t canlink_isr_tx(can_frame_t *out)
{
    uint8_t tail = tx_tail;
    if (tail == tx_head) {
        return -1;
    }
    *out = txq[tail & TXQ_MASK];
    tx_tail = (uint8_t)(tail + 1u);
    return 0;
}

/* ------------------------------------------------------------------ receiving */

static void hand_over(const uint8_t *bytes, uint8_t n)
{
    uint8_t i;
    for (i = 0; i < n; i++) {
        (void)uart_isr_rx(bytes[i]); /* a full ring drops it: the parser counts the broken frame */
    }
}

/* A message lost in assembly: one frame the parser counts as a framing error (1 byte). */
static void broken(void)
{
    static const uint8_t lost[4] = {0x00u, 0x02u, 0x01u, 0x00u};
    hand_over(lost, sizeof lost);
}

void canlink_isr_rx(uint16_t id, const uint8_t *data, uint8_t dlc)
{
    static const uint8_t delim = 0;
    uint8_t index, size;
    if (id != CANLINK_ID(CANLINK_SLOT_CMD) || dlc == 0u) {
        return;
    }
    index = data[0] & 0x0Fu;
    size = (uint8_t)(((data[0] >> 4) & 0x07u) + 1u);
    if (size > dlc - 1u) {
        size = (uint8_t)(dlc - 1u);
    }
    if (index == 0u) {
        if (seg_next) {
            broken();
        }
        seg_len = 0;
        seg_bad = 0;
    } else if (index != seg_next) {
        if (seg_next) {
            broken();
        }
        seg_next = 0;
        return;
    }
    if (seg_len + size > PROTO_MAX_FRAME) {
        seg_bad = 1;
    } else {
        memcpy(seg + 1 + seg_len, data + 1, size);
        seg_len = (uint8_t)(seg_len + size);
    }
    seg_next = (uint8_t)(index + 1u);
    if (!(data[0] & SEG_LAST)) {
        return;
    }
    seg_next = 0;
    if (seg_bad || seg_len == 0u) {
        broken();
        return;
    }
    hand_over(&delim, 1);
    hand_over(seg, (uint8_t)cobs_encode_inplace(seg, seg_len));
    hand_over(&delim, 1);
}
