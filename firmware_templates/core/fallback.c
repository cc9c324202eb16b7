/* fallback.c - see fallback.h. */
#include "fallback.h"

#include "drive.h"
#include "fault.h"
#include "imucheck.h"
#include "limbmap.h"
#include "proto.h"
#include "rom.h"
#include "safety.h"
#include "seq.h"
#include "tx.h"

#if CFG_FALLBACK
static void fall_back(uint8_t act)
{
    cfg_state_t steps[FALLBACK_MAX_STEPS];
    uint8_t dir = drive_dir();
    uint8_t k = (uint8_t)(act * 2u + (dir == PROTO_DIR_MINUS_X ? 1u : 0u));
    uint8_t n = ROM_U8(&limbmap_fb_len[k]);
    uint16_t first = ROM_U16(&limbmap_fb_first[k]);
    if (dir > PROTO_DIR_MINUS_X || limbmap_lost() != LIMBMAP_NONE || n == 0u || n > FALLBACK_MAX_STEPS) {
        return; /* a loaded gait whose way START left unstated (a learning probe) stops on its fault */
    }
    ROM_COPY(steps, &limbmap_fb_steps[first], n * sizeof steps[0]); /* both cfg_state_t */
    if (seq_load(steps, n, 0) != SEQ_OK) {
        return;
    }
    limbmap_use(act, limbmap_fb_map[k]);
    fault_clear();
    guard_ack(); /* the thermal budget (sma.c) is not refunded */
    seq_start(SEQ_DIR_LOADED, 0, imucheck_measured());
    drive_started(PROTO_GAIT_USER, dir);
    tx_event(PROTO_EV_FALLBACK, act, n);
    tx_event(PROTO_EV_GAIT_STARTED, PROTO_GAIT_USER, dir);
}
#endif

void fallback_fault(uint8_t code, uint16_t detail)
{
    uint8_t act;
    uint16_t from = (uint16_t)imucheck_measured();
    uint16_t transition = 0xFFFFu;
    if (code == PROTO_FAULT_SMA_ON_LIMIT) {
        act = (uint8_t)detail;
    } else if (code == PROTO_FAULT_STATE_TIMEOUT) {
        act = detail < CFG_N_LIMBS ? limbmap_actuator((uint8_t)detail) : LIMBMAP_NONE; /* the limb off its target: its coil */
    } else {
        return;
    }
    if (CFG_N_STATES <= 255u && from < CFG_N_STATES) {
        transition = (uint16_t)(from * (uint16_t)CFG_N_STATES + (uint16_t)seq_target());
    }
    tx_event(PROTO_EV_SUSPECT, act, transition);
#if CFG_FALLBACK
    if (act < CFG_N_ACTUATORS) {
        fall_back(act);
    }
#endif
}
