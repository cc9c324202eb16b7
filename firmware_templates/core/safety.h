/* safety.h - the step guard: state timeout on real time and latched on-limit hits.
 *
 * Contract. The guard watches what the gait demands, on hal_micros() (wrap-safe), not on
 * ticks. Time spent demanding a target that has not been reached accumulates from the
 * first demand and is NOT reset by STOP, START, ESTOP or LOAD_GAIT: only reaching a
 * target (the sequencer's REACHED) or the operator acknowledging a fault (guard_ack, on
 * CLEAR(FAULTS) of a latched fault) resets it. On-limit hits count until every coil that
 * hit has since heated above the hold ceiling on the way to a target reached (sma.h,
 * sma_take_heated; a START begins that record afresh): reaching states that other coils
 * make is no progress for a coil that cannot lift its own, and a host restarting the gait
 * past a dead coil re-reaches exactly those. Each coil's own time heated towards targets
 * not reached is kept the same way (STOP and START do not reset it) and times out as the
 * step does: restarts faster than the coil's on-time limit no longer keep a dead coil
 * demanded. When the step's or a coil's time passes the state timeout, or CFG_ON_LIMIT_LATCH
 * hits add up, the guard reports a fault for the caller to latch; the coil it names for the
 * latch is the one heated longest without progress (the last that hit when none has such
 * time). The thermal budget itself lives in sma.c and nothing here refunds it.
 */
#ifndef PROLEG_SAFETY_H
#define PROLEG_SAFETY_H

#include <stdint.h>

#include "robot_config.h"

#ifndef CFG_ON_LIMIT_LATCH
#define CFG_ON_LIMIT_LATCH 3u
#endif

#define GUARD_OK 0u
#define GUARD_TIMEOUT 1u  /* the demanded target was not reached in time */
#define GUARD_ON_LIMIT 2u /* repeated on-limit hits on one step */
/* guard_suspect when no coil is suspected: no actuator has this index (limbmap's are < CFG_N_ACTUATORS). */
#define GUARD_NO_SUSPECT 0xFFu

void guard_init(void);

/* Narrow the state timeout (ms; a value above CFG_STATE_TIMEOUT_MS counts as it). */
void guard_set_timeout_ms(uint32_t ms);

/* Once per tick after the sequencer and sma_tick. demanding: a gait is running and its
 * current target is not yet reached; reached: the sequencer reported REACHED this tick;
 * hits: on-limit bits from sma_tick. Takes sma_take_heated every tick. Returns GUARD_*;
 * with GUARD_ON_LIMIT, *act is the coil suspected (guard_suspect: the longest heated without
 * progress; the last that hit when none has such time).
 * GUARD_TIMEOUT only when `demanding` (drive.c relies on it). */
uint8_t guard_tick(uint8_t demanding, uint8_t reached, uint8_t hits, uint8_t *act);

/* The operator acknowledged a fault: the step's time and hit count start again. */
void guard_ack(void);

/* A START: what heated before it made no progress in it (drive.c). */
void guard_started(void);

/* The actuator heated longest while a target was demanded since it last heated on the way
 * to a target reached (kept across STOP and START; the lowest of equals), as of the last
 * guard_tick; when none has such time, the last that hit in that tick, else GUARD_NO_SUSPECT
 * (not coil 0: drive.c would then name coil 0's limb whenever it is off its level). */
uint8_t guard_suspect(void);

/* Time (µs) spent demanding an unreached target, and on-limit hits counting towards the latch. */
uint32_t guard_unreached_us(void);
uint8_t guard_hits(void);

#endif /* PROLEG_SAFETY_H */
