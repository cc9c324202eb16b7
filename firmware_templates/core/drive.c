/* drive.c - see drive.h. */
#include "drive.h"

#include "ctl.h"
#include "fault.h"
#include "imucheck.h"
#include "initzero.h"
#include "limbmap.h"
#include "param.h"
#include "proto.h"
#include "psi.h"
#include "safety.h"
#include "seq.h"
#include "sma.h"
#include "telemetry.h"
#include "tx.h"

static uint8_t gait, dir; /* gait last started */
static uint8_t seen;      /* the sequencer's events this tick (SEQ_EV_*; 0 when it did not run) */
typedef char drive_dir_starts_at_zero[PROTO_DIR_PLUS_X == 0 ? 1 : -1];

void drive_init(void)
{
    INIT_ZERO(gait);
    INIT_ZERO(dir); /* PROTO_DIR_PLUS_X */
    INIT_ZERO(seen);
}

#if defined(__GNUC__)
__attribute__((noinline)) /* START and the fallback: one copy */
#endif
void drive_started(uint8_t g, uint8_t d)
{
    gait = g;
    dir = d;
    guard_started(); /* safety: what heated before this START made no progress in it */
    ctl_reset(); /* a new gait: no stall or hold state carried over from the last one */
}

uint8_t drive_gait(void)
{
    return gait;
}

uint8_t drive_dir(void)
{
    return dir;
}

/* The limb not at its level of `target` driven by the coil heated longest without progress
 * (safety.h guard_suspect; the first such), else the last limb off its level: a healthy limb
 * sagging while the gait waits on a failed one is not the one suspected. DRIVE_NO_LIMB if every limb is at its level (the step
 * timed out only because one would not settle: no coil to suspect, fallback.c). */
static uint16_t limb_off_target(cfg_state_t target)
{
    uint8_t want[CFG_N_LIMBS];
    uint8_t i;
    uint16_t limb = DRIVE_NO_LIMB;
    seq_state_levels(target, want);
    for (i = CFG_N_LIMBS; i-- > 0;) {
        if (psi_level(i) != want[i] && (limb == DRIVE_NO_LIMB || limbmap_actuator(i) == guard_suspect())) {
            limb = i;
        }
    }
    return limb;
}

static uint8_t all_settled(void)
{
    uint8_t i;
    for (i = 0; i < CFG_N_LIMBS; i++) {
        if (!psi_settled(i)) {
            return 0;
        }
    }
    return 1;
}

void drive_step(void)
{
    uint8_t ev, step;
    cfg_state_t target;
    uint16_t measured = imucheck_measured();
    seen = 0;
    if (!seq_running() || measured == IMUCHECK_UNKNOWN) {
        return;
    }
    step = seq_step_byte();
    target = seq_target();
#if SEQ_CLOCK_PAUSE
    seq_pause_clock(ctl_coming_down()); /* the last tick's verdict (ctl.h, CTL_FALL_PROGRESS_MS) */
#endif
    /* The step counts as reached only once every limb is settled clear of its band
     * edges (psi_settled): until then the sequencer is shown a state that is not
     * the target (target ^ 1 differs from target by construction). */
    ev = seq_tick(all_settled() ? (cfg_state_t)measured : (cfg_state_t)(target ^ 1u));
    seen = ev;
    if (ev & SEQ_EV_REACHED) {
        tx_event(PROTO_EV_STATE_REACHED, step, target);
    }
    if (ev & SEQ_EV_TIMEOUT) {
        fault_raise_stopped(PROTO_FAULT_STATE_TIMEOUT, limb_off_target(target));
    }
}

#if defined(__GNUC__)
__attribute__((noinline)) /* smaller out of line: less register pressure in the tick (measured) */
#endif
void drive_apply(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    uint8_t i, hits, guard, act = 0;
    /* demanding: away from the target (not reached yet, or lost since: the sequencer reports
     * REACHED once a step, so a lost target's time counts until the step moves on), or just
     * moved on to the next (time lost after a step's REACHED carries into the next step's
     * until that is reached: docs/safety.md) */
    uint8_t demanding = (uint8_t)((seen & (SEQ_EV_AWAY | SEQ_EV_ADVANCED)) && seq_running() && !fault_latched());
    if (seq_running() && !fault_latched() && !sma_estopped() && imucheck_measured() != IMUCHECK_UNKNOWN) {
        uint8_t want[CFG_N_LIMBS];
        seq_state_levels(seq_target(), want);
        ctl_demand(want, param_drive_pm(), param_hold_pm(), duty);
    } else {
        for (i = 0; i < CFG_N_ACTUATORS; i++) {
            duty[i] = 0;
        }
    }
    for (i = 0; i < CFG_N_ACTUATORS; i++) {
        sma_request(i, duty[i]);
    }
#if CFG_FALLBACK_KEEPS_LOST
    /* safety: a coil the fallback gave up is not heated until the operator takes it back
     * (limbmap.h; LIMBMAP_NONE is no actuator: sma_request ignores it). A fallback that leaves
     * a limb on its lost coil ("dead": inchworm-3, caterpillar-4, planar-4) keeps it in the
     * map, and a gait the host loaded after the fallback that raised that limb heated the
     * given-up coil again, up to the state timeout, with no operator's word. */
    sma_request(limbmap_lost(), 0);
#endif
    hits = sma_tick((uint8_t)!demanding); /* holding a reached target, or not running (all off) */
    if (sma_take_clamped()) {
        telemetry_note_clamped();
    }
    /* safety: the step guard (safety.h) runs on real time from the first demand of an
     * unreached target; a START, STOP or ESTOP does not reset it. */
#if SEQ_CLOCK_PAUSE
    if (ctl_coming_down()) {
        demanding = 0; /* a fall still coming down, nothing heated past the hold: its time stands (ctl.h) */
    }
#endif
    guard = guard_tick(demanding, (uint8_t)(seen & SEQ_EV_REACHED), hits, &act);
    if (guard == GUARD_ON_LIMIT && !fault_latched()) {
        fault_raise(PROTO_FAULT_SMA_ON_LIMIT, act); /* repeated hits on one step: latched */
        return;
    }
    /* GUARD_TIMEOUT comes only with `demanding` (safety.h): a gait running and no fault
     * latched, just now; guard_tick changes neither, so they are not tested again here (R1 16 B
     * smaller on the Nano). */
    if (guard == GUARD_TIMEOUT) {
        fault_raise(PROTO_FAULT_STATE_TIMEOUT, limb_off_target(seq_target()));
        return;
    }
    for (i = 0; hits; i++, hits >>= 1) {
        if (hits & 1u) {
            /* A single hit is reported, not latched: the channel cools down and the gait
             * goes on; CFG_ON_LIMIT_LATCH hits without progress latch a fault (above). */
            tx_event(PROTO_EV_FAULT, PROTO_FAULT_SMA_ON_LIMIT, i);
        }
    }
}
