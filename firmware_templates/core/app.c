/* app.c - see app.h: the order of one tick; each step is its own module. */
#include "app.h"

#include "cmd.h"
#include "drive.h"
#include "fault.h"
#include "imucheck.h"
#include "param.h"
#include "proto.h"
#include "psi.h"
#include "robot_config.h"
#include "seq.h"
#include "sma.h"
#include "telemetry.h"
#include "tx.h"
#include "uart.h"

static uint32_t ms;     /* firmware time */
static uint16_t us_acc; /* µs of the current ms */

uint32_t app_time_ms(void)
{
    return ms;
}

void app_init(void)
{
    uint8_t i;
    ms = 0;
    us_acc = 0;
    uart_init();
    tx_init();
    fault_init();
    param_init();
    telemetry_init();
    drive_init();
    imucheck_init();
    sma_init();
    psi_init();
    seq_init();
    cmd_init();
    cmd_send_info(0);
    tx_event(PROTO_EV_BOOT, 0, 0);
    for (i = 0; i < CFG_N_LIMBS; i++) {
        imucheck_start(i);
    }
}

void app_tick(void)
{
    us_acc = (uint16_t)(us_acc + CFG_TICK_US);
    while (us_acc >= 1000u) {
        us_acc = (uint16_t)(us_acc - 1000u);
        ms++;
    }
    cmd_poll();            /* 1. commands (ESTOP: MOSFETs off first) */
    imucheck_read();       /* 2. IMUs -> measured state */
    drive_step();          /* 3. sequencer */
    drive_apply();         /* 3., 4. duties under the safety envelope */
    fault_watchdog_tick(); /* 5. link watchdog */
    telemetry_tick();      /* 5. telemetry */
}
