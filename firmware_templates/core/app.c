/* app.c - see app.h: the order of one tick; each step is its own module. */
#include "app.h"

#include "cmd.h"
#include "count.h"
#include "ctl.h"
#include "drive.h"
#include "fault.h"
#include "hal.h"
#include "imucheck.h"
#include "initzero.h"
#include "limbmap.h"
#include "param.h"
#include "proto.h"
#include "psi.h"
#include "robot_config.h"
#include "safety.h"
#include "seq.h"
#include "sma.h"
#include "telemetry.h"
#include "tx.h"
#include "uart.h"

/* hal.h's reset causes are the protocol's (BOOT's code goes out unchanged). */
typedef char app_reset_causes_match[(HAL_RESET_WATCHDOG == PROTO_RESET_WATCHDOG &&
                                     HAL_RESET_BROWN_OUT == PROTO_RESET_BROWN_OUT &&
                                     HAL_RESET_SOFTWARE == PROTO_RESET_SOFTWARE) ? 1 : -1];

/* Overruns in a row, saturating: only compared with CFG_OVERRUN_FAULT, so a byte does where
 * that is below its ceiling (the same comparisons; R1 on the Nano: issue 11). */
#if CFG_OVERRUN_FAULT < 0xFFu
typedef uint8_t overrun_run_t;
#define OVERRUN_RUN_MAX 0xFFu
#else
typedef uint16_t overrun_run_t;
#define OVERRUN_RUN_MAX 0xFFFFu
#endif

static struct {
    uint32_t ms;               /* firmware time: real time (hal_micros), not a tick count */
    uint32_t ms_us;            /* hal_micros() at which `ms` last counted a whole ms */
    overrun_run_t overrun_run; /* overruns in a row */
} st;
static uint32_t overruns; /* ticks whose work ended after the next tick was due (its own
                           * symbol: the avr-emu tests read it) */

uint32_t app_time_ms(void)
{
    return st.ms;
}

void app_init(void)
{
    uint8_t i;
    uint8_t cause = hal_reset_cause();
    uint8_t kept;
    INIT_ZERO(st); /* again on host-sim's reset */
    INIT_ZERO(overruns);
    st.ms_us = hal_micros();
    uart_init();
    tx_init();
    fault_init();
    param_init();
    telemetry_init();
    drive_init();
    imucheck_init();
    kept = sma_init(cause != HAL_RESET_POWER_ON);
    guard_init(); /* safety: the step guard on real time */
    psi_init();
    ctl_reset();
    limbmap_init();
    seq_init();
    cmd_init(kept);
    cmd_send_info(0);
    tx_event(PROTO_EV_BOOT, cause, kept);
    for (i = 0; i < CFG_N_LIMBS; i++) {
        imucheck_power_up(i);
    }
}

void app_tick_done(uint8_t overran)
{
    if (!overran) {
        st.overrun_run = 0;
        return;
    }
    count_up(&overruns);
    if (st.overrun_run < OVERRUN_RUN_MAX) {
        st.overrun_run++;
    }
    if (st.overrun_run >= CFG_OVERRUN_FAULT && !fault_latched()) {
        fault_raise(PROTO_FAULT_TICK_OVERRUN, 0); /* the timing the envelope assumes is gone */
    }
}

uint32_t app_overruns(void)
{
    return overruns;
}

void app_clear_overruns(void)
{
    overruns = 0;
}

void app_idle(uint32_t until_next_tick_us)
{
    imucheck_service();
    telemetry_idle(until_next_tick_us);
}

void app_tick(void)
{
    uint32_t now = hal_micros();
    while ((uint32_t)(now - st.ms_us) >= 1000u) { /* wrap-safe; no division: about one ms per tick */
        st.ms_us += 1000u;
        st.ms++;
    }
    cmd_poll();            /* 1. commands (ESTOP: MOSFETs off first) */
    imucheck_read();       /* 2. IMUs -> measured state */
    drive_step();          /* 3. sequencer */
    drive_apply();         /* 3., 4. duties under the safety envelope */
    fault_watchdog_tick(); /* 5. link watchdog */
    telemetry_tick();      /* 5. telemetry */
}
