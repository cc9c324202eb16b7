/* main.c - the firmware's entry on a board that runs its own loop: hal_init(), app_init(),
 * then one app_tick() every CFG_TICK_US.
 *
 * Contract. Ticks are paced on hal_micros(): each tick starts CFG_TICK_US after the
 * previous tick's start; a tick that overran by more than a whole period restarts the
 * schedule from now (no burst of catch-up ticks). Boards whose host drives the ticks
 * (host-sim: sim_run_ticks) leave this file out of the image (board file
 * [build] main_loop = false).
 *
 * A tick whose work ends after the next tick was due is an overrun: reported to
 * app_tick_done() (counted, and a fault after [control] overrun_fault in a row), never
 * silently absorbed. Each tick's work is framed by hal_tick_mark(1) / hal_tick_mark(0) (the emulators and a
 * logic probe time it), and the watchdog is fed only after a tick's work has returned.
 * The wait is its own function with `next_tick` its schedule, so the emulators can find
 * it in the ELF and skip idle time (docs/emulators-arm.md).
 */
#include <stdint.h>

#include "app.h"
#include "hal.h"
#include "robot_config.h"

uint32_t next_tick;

void wait_tick(void);

void __attribute__((noinline)) wait_tick(void)
{
    uint32_t now = hal_micros();
    uint32_t due = next_tick; /* in a register across app_idle, which leaves next_tick alone */
    if ((int32_t)(now - due) > (int32_t)CFG_TICK_US) {
        next_tick = due = now; /* overran by more than a tick: resynchronise */
    }
    for (;;) {
        int32_t left = (int32_t)(due - hal_micros());
        if (left <= 0) {
            break;
        }
        app_idle((uint32_t)left);
    }
    next_tick = due + CFG_TICK_US;
}

int main(void)
{
    hal_init();
    app_init();
    /* the schedule starts once everything is initialised: app_init's time (about 1 ms on
     * the Nano: psi_init's tables) is not a late first tick, nor a first-tick overrun */
    next_tick = hal_micros() + CFG_TICK_US;
    for (;;) {
        wait_tick();
        hal_tick_mark(1);
        app_tick();
        hal_tick_mark(0);
        app_tick_done((int32_t)(hal_micros() - next_tick) > 0); /* next_tick: the next tick's start */
        hal_watchdog_feed();
    }
}
