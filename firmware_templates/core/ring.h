/* ring.h - a byte ring shared by one interrupt handler and the main loop.
 *
 * Contract. One producer and one consumer, each either an interrupt handler or the main
 * loop, never both on the same side: no critical section is needed. head and tail
 * count bytes in and out freely (they wrap), so a ring holds exactly its size in bytes;
 * the size is a power of two and the caller passes size - 1 (a constant, so the
 * inlined code is a few instructions in an interrupt handler). Index reads and writes
 * must be single accesses on the MCU: rings of at most 128 bytes use 8-bit indices
 * (safe on 8-bit MCUs), larger rings 16-bit ones (RING_LARGE; only on MCUs with atomic
 * 16-bit loads and stores). Every call is O(1) and never waits; a full ring refuses
 * the byte.
 */
#ifndef PROLEG_RING_H
#define PROLEG_RING_H

#include <stdint.h>

#include "robot_config.h"

#if CFG_UART_RX_BYTES > 128 || CFG_UART_TX_BYTES > 128
#define RING_LARGE 1
typedef uint16_t ring_index_t;
#else
#define RING_LARGE 0
typedef uint8_t ring_index_t;
#endif

typedef struct {
    volatile ring_index_t head, tail; /* bytes in, bytes out (wrapping) */
} ring_t;

static inline void ring_clear(ring_t *r)
{
    r->head = 0;
    r->tail = 0;
}

/* 0 = queued, -1 = full (byte dropped). */
static inline int8_t ring_put(ring_t *r, volatile uint8_t *buf, ring_index_t mask, uint8_t b)
{
    ring_index_t head = r->head;
    if ((ring_index_t)(head - r->tail) > mask) {
        return -1;
    }
    buf[head & mask] = b;
    r->head = (ring_index_t)(head + 1u);
    return 0;
}

/* Next byte, or -1 when empty. */
static inline int ring_get(ring_t *r, const volatile uint8_t *buf, ring_index_t mask)
{
    ring_index_t tail = r->tail;
    uint8_t b;
    if (tail == r->head) {
        return -1;
    }
    b = buf[tail & mask];
    r->tail = (ring_index_t)(tail + 1u);
    return b;
}

#endif /* PROLEG_RING_H */
