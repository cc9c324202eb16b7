/* drive.c - see drive.h. */
#include "drive.h"

#include "ctl.h"
#include "fault.h"
#include "imucheck.h"
#include "param.h"
#include "proto.h"
#include "psi.h"
#include "seq.h"
#include "sma.h"
#include "telemetry.h"
#include "tx.h"

static uint8_t gait, dir; /* gait last started */

void drive_init(void)
{
    gait = 0;
    dir = PROTO_DIR_PLUS_X;
}

void drive_started(uint8_t g, uint8_t d)
{
    gait = g;
    dir = d;
}

uint8_t drive_gait(void)
{
    return gait;
}

uint8_t drive_dir(void)
{
    return dir;
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
    uint8_t ev, i;
    uint16_t step;
    cfg_state_t target;
    uint32_t measured = imucheck_measured();
    if (!seq_running() || measured == IMUCHECK_UNKNOWN) {
        return;
    }
    step = seq_step();
    target = seq_target();
    /* The step counts as reached only once every limb is settled clear of its band
     * edges (psi_settled): until then the sequencer is shown a state that is not
     * the target (target ^ 1 differs from target by construction). */
    ev = seq_tick(all_settled() ? (cfg_state_t)measured : (cfg_state_t)(target ^ 1u));
    if (ev & SEQ_EV_REACHED) {
        tx_event(PROTO_EV_STATE_REACHED, (uint8_t)(step > 255u ? 255u : step), target);
    }
    if (ev & SEQ_EV_TIMEOUT) {
        uint8_t want[CFG_N_LIMBS];
        uint16_t limb = 0;
        seq_state_levels(target, want);
        for (i = 0; i < CFG_N_LIMBS; i++) {
            if (psi_level(i) != want[i]) {
                limb = i;
                break;
            }
        }
        fault_raise_stopped(PROTO_FAULT_STATE_TIMEOUT, limb);
    }
}

void drive_apply(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    uint8_t i, hits;
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
    hits = sma_tick();
    if (sma_take_clamped()) {
        telemetry_note_clamped();
    }
    for (i = 0; i < CFG_N_ACTUATORS; i++) {
        if (hits & (1u << i)) {
            /* Reported, not latched: the channel cools down and the gait goes on; a limb
             * that cannot reach its state then ends in a state timeout. */
            tx_event(PROTO_EV_FAULT, PROTO_FAULT_SMA_ON_LIMIT, i);
        }
    }
}
