/* safety.c - see safety.h. */
#include "safety.h"

#include "elapsed.h"
#include "hal.h"
#include "sma.h"

static uint32_t last_us;
static uint32_t unreached_us;
static uint32_t timeout_us; /* set by guard_init (no .data bytes in flash) */
static uint8_t hits_since_reached;
/* The hit count is a byte: it stops at the latch, reached in a tick in which every coil may hit. */
typedef char guard_hits_fit_a_byte[(CFG_ON_LIMIT_LATCH - 1u + CFG_N_ACTUATORS <= 255u) ? 1 : -1];
static uint8_t hit_mask; /* actuators hit since each last heated on the way to a target reached */

#if defined(__GNUC__)
__attribute__((noinline)) /* smaller out of line (measured) */
#endif
void guard_init(void)
{
    last_us = hal_micros();
    guard_ack();
    guard_set_timeout_ms(CFG_STATE_TIMEOUT_MS);
}

#if defined(__GNUC__)
__attribute__((noinline)) /* guard_init and SET_PARAM: one copy */
#endif
void guard_set_timeout_ms(uint32_t ms)
{
    timeout_us = (ms < CFG_STATE_TIMEOUT_MS ? ms : CFG_STATE_TIMEOUT_MS) * 1000UL;
}

uint8_t guard_tick(uint8_t demanding, uint8_t reached, uint8_t hits, uint8_t *act)
{
    uint32_t dt = elapsed_us(&last_us); /* wrap-safe; a backwards step or a stall capped as sma.c */
    uint8_t i;
    if (reached) {
        /* A coil that hit and has since heated on the way to this target made progress;
         * reaching what the other coils make is none for it (safety.h). The step's time
         * starts again either way; the hits do only once every coil that hit progressed.
         * (guard_ack then putting back what stays: R1 8 B smaller on the Nano.) */
        uint8_t hit = (uint8_t)(hit_mask & ~sma_take_heated()), n = hits_since_reached;
        guard_ack();
        if (hit) {
            hit_mask = hit;
            hits_since_reached = n;
        }
    }
    hit_mask |= hits;
    for (i = 0; hits; i++, hits >>= 1) {
        if (hits & 1u) {
            *act = i;
            hits_since_reached++; /* no saturation: once it reaches the latch no coil is driven (guard_hits_fit_a_byte) */
        }
    }
    if (hits_since_reached >= CFG_ON_LIMIT_LATCH) {
        return GUARD_ON_LIMIT;
    }
    if (demanding) {
        uint32_t u = unreached_us + dt;
        unreached_us = u < dt ? 0xFFFFFFFFUL : u; /* saturates: the sum wrapped iff it is below dt */
        if (unreached_us >= timeout_us) {
            return GUARD_TIMEOUT;
        }
    }
    return GUARD_OK;
}

#if defined(__GNUC__)
__attribute__((noinline)) /* four callers: one copy */
#endif
void guard_ack(void)
{
    unreached_us = 0;
    hits_since_reached = 0;
    hit_mask = 0;
}

uint32_t guard_unreached_us(void)
{
    return unreached_us;
}

uint8_t guard_hits(void)
{
    return hits_since_reached;
}
