/* param.h - SET_PARAM: the run-time parameters and the table that checks them.
 *
 * Contract. One descriptor per ParamId (proleg/protocol/definition.py) says where the
 * parameter lives (the function that applies it), its sane range (outside: NACK
 * OUT_OF_RANGE), its safety range (outside, but in range: NACK SAFETY_LIMIT; the build's
 * envelope, which a command may narrow but never widen) and its scale (a value in ms is
 * turned into ticks, rounded up, before it is applied). param_set() returns 0 when the
 * value was applied, else the PROTO_ERR_* code and nothing changed (except a hysteresis
 * refused part-way: the thresholds before the refused one keep the new width). The
 * parameters stored here start at the build's values (param_init).
 */
#ifndef PROLEG_PARAM_H
#define PROLEG_PARAM_H

#include <stdint.h>

void param_init(void);

/* Returns 0 (accepted) or a PROTO_ERR_* code. */
uint8_t param_set(uint8_t param, uint8_t index, int32_t value);

uint16_t param_drive_pm(void);
uint16_t param_hold_pm(void);
uint32_t param_watchdog_us(void); /* the link watchdog (whole ticks of CFG_TICK_US), 0 = off */

#endif /* PROLEG_PARAM_H */
