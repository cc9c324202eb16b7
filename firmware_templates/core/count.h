/* count.h - one out-of-line 32-bit counter increment, shared by every counter in the
 * firmware (statistics, overruns, the sequencer's tick counts): on an 8-bit MCU a call is
 * shorter than each inline copy of a 32-bit increment. */
#ifndef PROLEG_COUNT_H
#define PROLEG_COUNT_H

#include <stdint.h>

void count_up(uint32_t *counter);

#endif
