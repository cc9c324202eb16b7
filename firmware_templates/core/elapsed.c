/* elapsed.c - see elapsed.h. */
#include "elapsed.h"

#include "hal.h"
#include "robot_config.h"

#if defined(__GNUC__)
__attribute__((noinline)) /* one copy for both callers on the 8-bit targets */
#endif
uint32_t elapsed_us(uint32_t *last_us)
{
    uint32_t now = hal_micros();
    uint32_t dt = now - *last_us; /* unsigned: right across the 2^32 wrap */
    *last_us = now;
    if (dt >= 0x80000000UL) {
        dt = CFG_TICK_US; /* the clock stepped back: count one tick */
    } else if (dt > ELAPSED_CAP_US) {
        dt = ELAPSED_CAP_US;
    }
    return dt;
}
