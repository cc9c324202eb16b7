/* elapsed.h - real time since the last call, for the envelope's clocks (sma.c, safety.c).
 *
 * Contract. elapsed_us(&last) returns hal_micros() − last (unsigned: right across the 2^32
 * wrap) and sets last to now. A backwards step of the clock (a difference of 2^31 or more)
 * counts as one tick, CFG_TICK_US; a gap longer than ELAPSED_CAP_US counts as that long (a
 * stalled loop is the hardware watchdog's job). One copy for both clocks.
 */
#ifndef PROLEG_ELAPSED_H
#define PROLEG_ELAPSED_H

#include <stdint.h>

#define ELAPSED_CAP_US 400000UL

uint32_t elapsed_us(uint32_t *last_us);

#endif /* PROLEG_ELAPSED_H */
