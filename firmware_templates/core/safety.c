/* safety.c - see safety.h. */
#include "safety.h"

#include <string.h>

#include "elapsed.h"
#include "hal.h"
#include "initzero.h"
#include "sma.h"

static uint32_t last_us;
static uint32_t timeout_us; /* set by guard_init (no .data bytes in flash) */
/* The tallies guard_ack clears, in one record: one memset instead of a store for each, and
 * guard_tick reaches them from one address (R1 34 B smaller on the Nano). */
static struct {
    uint32_t unreached_us;
    uint8_t hits_since_reached; /* a byte: guard_hits_fit_a_byte, below */
    uint8_t hit_mask; /* actuators hit since each last heated on the way to a target reached */
    /* Each coil's time heated while a target was demanded, since it last heated on the way to a
     * target reached. STOP and START keep it: a host restarting a gait past a dead coil
     * re-reaches the states the other coils make, which is no progress for it (safety.h). At
     * most timeout_us + one interval: past timeout_us, while demanding, the caller latches a fault
     * and nothing is demanded until guard_ack clears it. */
    uint32_t coil_us[CFG_N_ACTUATORS];
} tally;
/* The hit count is a byte: it stops at the latch, reached in a tick in which every coil may hit. */
typedef char guard_hits_fit_a_byte[(CFG_ON_LIMIT_LATCH - 1u + CFG_N_ACTUATORS <= 255u) ? 1 : -1];
static uint8_t progressed; /* actuators heated since the last target reached or START */
static uint8_t heating;    /* actuators heated in the interval the tick just charged */
static uint8_t demanded;   /* the last tick demanded a target (that interval's demand) */
/* This tick's coil with the most of that time (the lowest of equals); when no coil has any,
 * the last that hit in this tick, else GUARD_NO_SUSPECT. Set by guard_tick, read through
 * guard_suspect. */
static uint8_t suspect;

#if defined(__GNUC__)
__attribute__((noinline)) /* smaller out of line (measured) */
#endif
void guard_init(void)
{
    INIT_ZERO(progressed);
    INIT_ZERO(heating);
    INIT_ZERO(demanded);
    INIT_ZERO(suspect);
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
    uint32_t most = 0;
    /* the interval since the last tick heated the coils `heating` says, and belonged to a
     * demand if the last tick demanded: a STOP in this tick does not take it back */
    uint8_t i, was = demanded ? heating : 0u, made = 0;
    demanded = demanding;
    heating = sma_take_heated();
    if (reached) {
        /* A coil that hit and has since heated on the way to this target made progress;
         * reaching what the other coils make is none for it (safety.h). The step's time
         * starts again either way; the hits do only once every coil that hit progressed. */
        made = progressed;
        tally.hit_mask &= (uint8_t)~made;
        if (!tally.hit_mask) {
            tally.hits_since_reached = 0;
        }
        progressed = 0;
        tally.unreached_us = 0;
    }
    /* only now: what sma_tick just decided heats from this tick on, after this tick's reach. A
     * START that found its target reached and moved on in one tick (hold_ms 0) heated a dead
     * coil in that tick towards the next target, which counted as progress to the reached one:
     * restarted every 3 s, R1's dead right coil was heated 77 s of 120 s, no fault latched. */
    progressed |= heating;
    tally.hit_mask |= hits;
    suspect = GUARD_NO_SUSPECT; /* a latch always comes with a hit in this tick: never its act */
    for (i = 0; i < CFG_N_ACTUATORS; i++, was >>= 1, made >>= 1, hits >>= 1) {
        uint32_t t = tally.coil_us[i];
        if (was & 1u) {
            t += dt;
        }
        if (made & 1u) {
            t = 0; /* heated on the way to this target: progress */
        }
        tally.coil_us[i] = t;
        if (t > most) {
            most = t;
            suspect = i;
        }
        if (hits & 1u) {
            tally.hits_since_reached++; /* no saturation: once it reaches the latch no coil is driven (guard_hits_fit_a_byte) */
            if (!most) {
                suspect = i; /* no coil heated without progress (yet): the one that hit */
            }
        }
    }
    if (tally.hits_since_reached >= CFG_ON_LIMIT_LATCH) {
        /* the coil heated longest without progress (none: the last that hit), not the coil
         * that hit last, which may be a healthy one slow at a weak supply */
        *act = suspect;
        return GUARD_ON_LIMIT;
    }
    if (demanding) {
        uint32_t u = tally.unreached_us + dt;
        tally.unreached_us = u < dt ? 0xFFFFFFFFUL : u; /* saturates: the sum wrapped iff it is below dt */
        /* the step, or one coil over all the steps it heated towards and none reached */
        if (tally.unreached_us >= timeout_us || most >= timeout_us) {
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
    memset(&tally, 0, sizeof tally);
}

void guard_started(void)
{
    progressed = 0; /* what heated before this START made no progress in it */
}

uint8_t guard_suspect(void)
{
    return suspect;
}

uint32_t guard_unreached_us(void)
{
    return tally.unreached_us;
}

uint8_t guard_hits(void)
{
    return tally.hits_since_reached;
}
