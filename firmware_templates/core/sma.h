/* sma.h - SMA MOSFET drive and the thermal budget of every coil (the safety envelope).
 *
 * Contract. Every PWM duty the firmware sets goes through this module's one output
 * function, which clamps it to the duty ceiling (CFG_MAX_DUTY_PM, fixed at build time,
 * possibly narrowed at run time). Commands that ask for more are refused by the caller
 * (sma_set_limits refuses to widen); the clamp is the last line of defence.
 *
 * The budget runs on real time, hal_micros() (wrap-safe unsigned differences), never on
 * the tick count. Each sma_tick charges the interval since the previous one at the
 * highest duty the pin carried in it, then decides the next output. Per actuator:
 * - "on" means a duty above the hold ceiling CFG_HOLD_MAX_DUTY_PM (a duty the coil may
 *   carry forever: holding at or below it is never on-time);
 * - an on-time debt: every µs on adds a µs; every µs not on pays back max_on / min_cooldown
 *   µs, so ANY on-period of length L owes L × min_cooldown / max_on of cool-down;
 * - max on-time: the debt never exceeds max_on, so no on-period lasts longer than max_on,
 *   and on/off games cannot beat max_on / (max_on + min_cooldown) of the time on. A period
 *   that would pass it is cut one tick early (an on-limit hit, reported) and the coil then
 *   stays fully off until the debt is paid: min_cooldown after a full max_on;
 * - mean duty: the duty integrated over any window of CFG_DUTY_WINDOW_MS stays at or below
 *   CFG_MEAN_DUTY_PM (a request that would not fit gets 0; while a reached target is held,
 *   the first such tick of a request above the hold ceiling is an on-limit hit).
 * - the coil's heat (builds with CFG_COIL_TAU_MS, the coil's thermal time constant: the robot
 *   file's opt-in [safety] coil_heat_ceiling = true; none of its code otherwise): the duty
 *   the pin carried, smoothed with that time constant, is what a first-order coil's temperature
 *   follows; while it is at or above the mean-duty ceiling (as hot as that ceiling held for
 *   ever), a request above it gets the mean-duty ceiling (the duty that keeps it there). A coil
 *   weaker than the one the time constant was taken from (a mismatch, a draught) is cooler than
 *   its heat says and is held back with the others. Unlike the debt, whose
 *   pay-back (max_on / min_cooldown, 3.75× on the paper robots) is far faster than a coil cools,
 *   it forgives no heat: a STOP + START of a hot coil finds it as hot as it is.
 * Nothing resets the spent budget: sma_all_off() and sma_estop() turn the pins off at once
 * but the interval until the next sma_tick is still charged at the duty it had, so a
 * STOP + START in one tick continues the on-period. Only sma_init(0) (a power-on) starts
 * from a cold budget; after any other reset sma_init(1) keeps what the last run spent (the
 * time in reset counts as none). sma_estop() latches until sma_clear_estop(), across such a
 * reset too.
 */
#ifndef PROLEG_SMA_H
#define PROLEG_SMA_H

#include <stdint.h>

#include "elapsed.h"
#include "robot_config.h"

/* Defaults for builds whose robot_config.h predates these keys (see docs/safety.md). */
#ifndef CFG_HOLD_MAX_DUTY_PM
#define CFG_HOLD_MAX_DUTY_PM 3000u
#endif
#ifndef CFG_MEAN_DUTY_PM
#define CFG_MEAN_DUTY_PM 4500u
#endif
#ifndef CFG_DUTY_WINDOW_MS
#define CFG_DUTY_WINDOW_MS 10000UL
#endif

/* A gap between two sma_tick calls longer than this is charged as this long (a stalled
 * loop is the hardware watchdog's job); a backwards step of the clock as one tick. */
#define SMA_DT_CAP_US ELAPSED_CAP_US

/* warm: the chip reset without losing power (hal_reset_cause() not HAL_RESET_POWER_ON): keep
 * the budget this build's last run left in RAM, if it is there. Returns 1 if it kept it, 0 if
 * the budget starts cold (the BOOT event's detail). */
uint8_t sma_init(uint8_t warm);

/* Duty (permyriad) the controller wants for actuator `act` from the next sma_tick on. */
void sma_request(uint8_t act, uint16_t duty_pm);

/* Charge the time since the last call, then apply requests under the budget; returns a
 * bit per actuator whose on-period was cut at max_on this tick (an on-limit hit), or, with
 * `holding` (a gait holds a reached target: safety.h's demanding is 0), that the mean-duty
 * window began to refuse while it asked for more than the hold ceiling (also a hit). */
uint8_t sma_tick(uint8_t holding);

/* Every channel off at once; requests cleared. Not latched; refunds nothing. */
void sma_all_off(void);

/* Every channel off at once and latched until sma_clear_estop(). Refunds nothing. */
void sma_estop(void);
void sma_clear_estop(void);
uint8_t sma_estopped(void);

/* Narrow the envelope at run time. Returns 0, or -1 (nothing changed) when a value
 * would widen it: duty above CFG_MAX_DUTY_PM, on-time above CFG_MAX_ON_TICKS, cool-down
 * below CFG_MIN_COOLDOWN_TICKS; -2 (nothing changed) for a cool-down of 256 on-times or
 * more, which the debt's pay-back rate (1/256 steps) cannot express. Times in ticks of
 * CFG_TICK_US, enforced in microseconds. */
int8_t sma_set_limits(uint16_t max_duty_pm, uint32_t max_on_ticks, uint32_t cooldown_ticks);
uint16_t sma_max_duty(void);

/* The duty ceiling applied to every output. */
uint16_t sma_clamp(uint16_t duty_pm);

/* Duty applied to actuator `act` at the last output (permyriad). */
uint16_t sma_duty(uint8_t act);

/* 1 while actuator `act` may not heat: cooling after an on-limit hit, or its mean-duty
 * window is full. */
uint8_t sma_cooling(uint8_t act);

/* Actuator `act`'s on-time not yet paid back by cool-down (µs). */
uint32_t sma_debt_us(uint8_t act);

/* 1 when an output was clamped to the ceiling since the last call. */
uint8_t sma_take_clamped(void);

/* A bit per channel heated above the hold ceiling (on-time) since the last call; cleared. */
uint8_t sma_take_heated(void);

#endif /* PROLEG_SMA_H */
