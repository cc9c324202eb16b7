/* hal.h - the whole porting layer between proleg's portable core and a board.
 *
 * One implementation per board family: hal/avr, hal/stm32f1, hal/sim. Nothing above
 * this header knows which board it runs on. Every call is non-blocking or bounded:
 * the control tick must never wait on the host link.
 *
 * Real boards provide main(): app_init(); then forever { hal_wait_tick(); app_tick(); }.
 * The simulated board drives app_init()/app_tick() from sim_reset()/sim_run_ticks().
 */
#ifndef PROLEG_HAL_H
#define PROLEG_HAL_H

#include <stddef.h>
#include <stdint.h>

/* Clocks, tick timer (CFG_TICK_US), I2C at 400 kHz, PWM channels (all off), UART at
 * the board's baud rate. Called once before anything else. */
void hal_init(void);

/* Free-running microsecond counter; wraps at 2^32. */
uint32_t hal_micros(void);

/* Block until the next control tick boundary (real boards only). */
void hal_wait_tick(void);

/* One I2C transaction on the IMU bus: write ntx bytes, then (repeated start) read nrx
 * bytes; either count may be 0. Returns 0 on success, negative on NACK, bus error or
 * timeout (bounded: never longer than about 2 ms). */
int hal_i2c_write_read(uint8_t addr7, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx);

/* Set the MOSFET PWM duty of an actuator channel, in permyriad (0 = off, 10000 = on). */
void hal_pwm_set(uint8_t channel, uint16_t duty_permyriad);

/* Queue bytes for the host link; returns how many were queued (the rest are dropped
 * and counted by the caller: telemetry never stalls the control loop). */
uint16_t hal_uart_write(const uint8_t *data, uint16_t n);

/* Next byte received from the host link, or -1 when none is waiting. */
int hal_uart_read_byte(void);

/* Critical section (interrupts off); returns the state to restore. */
uint8_t hal_critical_enter(void);
void hal_critical_exit(uint8_t state);

#endif /* PROLEG_HAL_H */
