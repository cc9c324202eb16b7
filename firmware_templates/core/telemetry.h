/* telemetry.h - the periodic TELEMETRY frame and the status flags.
 *
 * Contract. telemetry_tick() runs once per tick and sends one TELEMETRY frame each time
 * the rate accumulator passes CFG_TICK_HZ, so the frames are spread evenly at the set
 * rate (0 = off; starts at CFG_TELEMETRY_HZ). Telemetry may use at most half the link
 * (UART bytes/s = baud/10) so that replies and events always find room in the transmit
 * queue: telemetry_set_rate() refuses a faster rate (returns nonzero, nothing changed).
 * The frame carries the firmware clock, the measured and target state, the gait last
 * started, the step, the flags (telemetry_flags()), ψ per limb (psi_last_centideg) and
 * the applied duty per actuator; DUTY_CLAMPED is set when an output was clamped since
 * the previous frame (telemetry_note_clamped()). The tick only takes the frame's values;
 * encoding and queueing it (CRC, COBS: a few hundred µs on an 8-bit MCU) is background
 * work, done by telemetry_idle() between ticks when the time left before the next tick
 * exceeds the longest encode seen so far (so it never delays a tick); a frame still
 * waiting when the next is taken is sent then, in the tick (and shows in its budget).
 */
#ifndef PROLEG_TELEMETRY_H
#define PROLEG_TELEMETRY_H

#include <stdint.h>

void telemetry_init(void);
void telemetry_tick(void);
void telemetry_idle(uint32_t until_next_tick_us);

/* 0 = accepted; nonzero = above the link's share (rate unchanged). */
uint8_t telemetry_set_rate(uint16_t hz);
uint16_t telemetry_rate(void);

void telemetry_note_clamped(void);
uint16_t telemetry_flags(void);

#endif /* PROLEG_TELEMETRY_H */
