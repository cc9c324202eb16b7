/* sma.h - SMA MOSFET drive and the safety envelope.
 *
 * Contract. Every PWM duty the firmware sets goes through this module's one output
 * function, which clamps it to the duty ceiling (CFG_MAX_DUTY_PM, fixed at build time,
 * possibly narrowed at run time). Commands that ask for more are refused by the caller
 * (sma_set_limits refuses to widen); the clamp is the last line of defence.
 * Per actuator: a channel that has been on for more than max_on ticks in a row is forced
 * off for cooldown ticks. sma_estop() turns every channel off before it returns and
 * latches until sma_clear_estop(). sma_all_off() turns every channel off now (fault, stop).
 */
#ifndef PROLEG_SMA_H
#define PROLEG_SMA_H

#include <stdint.h>

#include "robot_config.h"

void sma_init(void);

/* Duty (permyriad) the controller wants for actuator `act` from the next sma_tick on. */
void sma_request(uint8_t act, uint16_t duty_pm);

/* Apply requests under the envelope; returns a bit per actuator forced into cool-down
 * this tick (bit i = actuator i hit max continuous on-time). */
uint8_t sma_tick(void);

/* Every channel off at once; requests cleared. Not latched. */
void sma_all_off(void);

/* Every channel off at once and latched until sma_clear_estop(). */
void sma_estop(void);
void sma_clear_estop(void);
uint8_t sma_estopped(void);

/* Narrow the envelope at run time. Returns 0, or -1 (nothing changed) when a value
 * would widen it: duty above CFG_MAX_DUTY_PM, on-time above CFG_MAX_ON_TICKS, cool-down
 * below CFG_MIN_COOLDOWN_TICKS. */
int8_t sma_set_limits(uint16_t max_duty_pm, uint32_t max_on_ticks, uint32_t cooldown_ticks);
uint16_t sma_max_duty(void);

/* The duty ceiling applied to every output. */
uint16_t sma_clamp(uint16_t duty_pm);

/* Duty applied to actuator `act` at the last output (permyriad). */
uint16_t sma_duty(uint8_t act);

/* 1 while actuator `act` is in forced cool-down. */
uint8_t sma_cooling(uint8_t act);

/* 1 when an output was clamped to the ceiling since the last call. */
uint8_t sma_take_clamped(void);

/* Count of forced cool-downs since sma_init (saturates). */
uint16_t sma_limit_hits(void);

#endif /* PROLEG_SMA_H */
