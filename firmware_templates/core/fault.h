/* fault.h - the fault latch, stopping a gait, the link watchdog.
 *
 * Contract. fault_raise() turns every MOSFET off, latches the fault, reports it (EVENT
 * FAULT) and stops the gait (EVENT GAIT_STOPPED, reason FAULT) in the same call; the
 * latch stays until fault_clear() (CLEAR(FAULTS)), and while it is set no gait starts
 * and no actuator is driven. fault_stop_gait() stops a running gait and reports why
 * (nothing when none runs). The link watchdog: fault_watchdog_tick() runs once per
 * tick; when a gait runs and no valid frame has arrived for the watchdog period
 * (param.h, 0 = off) it turns every MOSFET off and stops the gait (reported, not
 * latched: a START clears the flag). fault_heard_host() restarts the count.
 */
#ifndef PROLEG_FAULT_H
#define PROLEG_FAULT_H

#include <stdint.h>

void fault_init(void);

/* Every MOSFET off, latch, EVENT FAULT(code, detail), then stop the gait. */
void fault_raise(uint8_t code, uint16_t detail);

/* The same for a gait the sequencer has already stopped by itself (state timeout):
 * every MOSFET off, latch, EVENT FAULT(code, detail), EVENT GAIT_STOPPED(FAULT). */
void fault_raise_stopped(uint8_t code, uint16_t detail);

/* Stop a running gait and send EVENT GAIT_STOPPED(reason, cycles); nothing if idle. */
void fault_stop_gait(uint8_t reason);

uint8_t fault_latched(void);
void fault_clear(void);

void fault_heard_host(void);
void fault_watchdog_tick(void);
uint8_t fault_watchdog_tripped(void);
void fault_watchdog_rearm(void);

#endif /* PROLEG_FAULT_H */
