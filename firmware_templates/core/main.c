/* main.c - the firmware's entry on a board that runs its own loop: hal_init(), app_init(),
 * then one app_tick() every CFG_TICK_US.
 *
 * Contract. Ticks are paced on hal_micros(): each tick starts CFG_TICK_US after the
 * previous tick's start; a tick that overran by more than a whole period restarts the
 * schedule from now (no burst of catch-up ticks). Boards whose host drives the ticks
 * (host-sim: sim_run_ticks) leave this file out of the image (board file
 * [build] main_loop = false).
 */
#include <stdint.h>

#include "app.h"
#include "hal.h"
#include "robot_config.h"

static uint32_t next_tick;

static void wait_tick(void)
{
    uint32_t now = hal_micros();
    if ((int32_t)(now - next_tick) > (int32_t)CFG_TICK_US) {
        next_tick = now; /* overran by more than a tick: resynchronise */
    }
    while ((int32_t)(hal_micros() - next_tick) < 0) {
    }
    next_tick += CFG_TICK_US;
}

int main(void)
{
    hal_init();
    next_tick = hal_micros() + CFG_TICK_US;
    app_init();
    for (;;) {
        wait_tick();
        app_tick();
    }
}
