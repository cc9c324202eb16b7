/* app.h - the firmware application: the order of one control tick.
 *
 * Contract. app_init() runs once after hal_init(): it initialises every module, wakes
 * and checks the IMUs, and sends an unsolicited INFO and a BOOT event. app_tick() runs
 * once per control tick (CFG_TICK_US) and, in this order:
 *   1. decodes the bytes the host sent and answers each command (an ESTOP turns every
 *      MOSFET off before anything else happens in this tick);
 *   2. reads each limb's MPU-6050 (6 accelerometer bytes), checks the data (no ACK twice
 *      in a row, |g| outside 0.5..1.5 g, identical samples for CFG_IMU_STUCK_SAMPLES) and
 *      classifies each limb's level (psi.h);
 *   3. steps the sequencer (seq.h) and turns the target into a duty per actuator (ctl.h);
 *   4. applies the duties under the safety envelope (sma.h);
 *   5. checks the link watchdog, then sends telemetry at the configured rate.
 * Any fault (state timeout, IMU) stops the gait and turns every MOSFET off in the tick it
 * is detected, and stays latched until CLEAR(FAULTS). E-stop latches until CLEAR(ESTOP).
 * Each step is one module: cmd.h (1), imucheck.h (2), drive.h (3, 4), fault.h and
 * telemetry.h (5); tx.h sends, param.h holds SET_PARAM's table. app_time_ms() is the
 * firmware clock (ms since app_init, on hal_micros: real time, not ticks) that stamps
 * events and telemetry.
 */
#ifndef PROLEG_APP_H
#define PROLEG_APP_H

#include <stdint.h>

void app_init(void);
void app_tick(void);
/* Between ticks, as often as the main loop likes, with the µs left before the next tick
 * (bounded, never waits, never starts what would not end before the next tick): moves
 * the background IMU transactions on and sends the telemetry frame (telemetry.h). */
void app_idle(uint32_t until_next_tick_us);
/* After each tick (core/main.c): whether its work ended after the next tick was due.
 * Counted (GET_STATS tick_overruns, CLEAR(COUNTERS) zeroes it); CFG_OVERRUN_FAULT in a
 * row (robot file [control] overrun_fault) latch FAULT TICK_OVERRUN. */
void app_tick_done(uint8_t overran);
uint32_t app_overruns(void);
void app_clear_overruns(void);
uint32_t app_time_ms(void);

#endif /* PROLEG_APP_H */
