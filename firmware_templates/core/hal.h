/* hal.h - the porting layer: everything the core needs from a board, and nothing else.
 *
 * Contract. One implementation per board family under hal/<family>/ (avr, stm32f1,
 * sim; hal/template/ to copy for a new MCU). Nothing above this header knows which
 * board it runs on. Every call is non-blocking or bounded: the control tick never
 * waits on the host link. The core owns main() and the tick pacing (main.c, on
 * hal_micros) and the UART byte rings (uart.h); a HAL only moves bytes between its
 * UART and those rings in its interrupt handlers: each received byte to uart_isr_rx(),
 * and, while the transmit interrupt is on, uart_isr_tx() until it returns -1.
 */
#ifndef PROLEG_HAL_H
#define PROLEG_HAL_H

#include <stddef.h>
#include <stdint.h>

/* Clocks, the microsecond counter, I2C at the board's rate, PWM channels (all off),
 * the UART at CFG_UART_BAUD with its receive interrupt on. Called once, first. */
void hal_init(void);

/* Free-running microsecond counter: monotonic, wraps at 2^32. */
uint32_t hal_micros(void);

/* One I2C transaction on the IMU bus, in the background: write ntx bytes from tx, then
 * (repeated start) read nrx bytes into rx, NACKing the last; either count may be 0 (not
 * both). tx and rx must stay valid until hal_i2c_poll() no longer returns HAL_I2C_BUSY.
 * Returns 0 when begun, negative if the previous transaction is still in flight. */
int8_t hal_i2c_begin(uint8_t addr7, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx);

/* The last begun transaction: HAL_I2C_BUSY while in flight, 0 done, negative on NACK,
 * bus error, or when HAL_I2C_DEADLINE_US have passed since it began (then it is aborted
 * and the bus recovered: a slave holding SDA gets up to 9 SCL clocks and a STOP). Never
 * waits; returns at once. */
#define HAL_I2C_BUSY 1
#define HAL_I2C_DEADLINE_US 1500u
int8_t hal_i2c_poll(void);

/* Why the chip last reset, one of HAL_RESET_* (the BOOT event's code; protocol
 * ResetCause). Read from the reset flags once in hal_init(), which also clears them so
 * the next reset reports its own cause. */
#define HAL_RESET_UNKNOWN 0u
#define HAL_RESET_POWER_ON 1u
#define HAL_RESET_EXTERNAL 2u
#define HAL_RESET_BROWN_OUT 3u
#define HAL_RESET_WATCHDOG 4u
#define HAL_RESET_SOFTWARE 5u
uint8_t hal_reset_cause(void);

/* Reload the hardware watchdog (started by hal_init). The core calls it once per
 * completed tick and nowhere else: a hung tick, a stuck bus wait or a dead core resets
 * the chip with every coil off. */
void hal_watchdog_feed(void);

/* Tick-budget marker: 1 when a tick's work starts, 0 when it ends. One store to a
 * register that does nothing else (AVR GPIOR0 bit 0; STM32 BKP_DR1, clock off: the chip
 * ignores it), so an emulator or a logic probe can time every tick. */
void hal_tick_mark(uint8_t busy);

/* hal_i2c_begin on the board's I2C bus `bus` (its index in the board file's [[i2c.bus]]
 * list; hal_i2c_begin is bus 0). One transaction at a time over all buses: hal_i2c_poll()
 * reports the last one begun, whichever bus it is on; -1 while it is in flight or for a
 * bus the board lacks. Needed only on boards with more than one bus: the core calls it
 * only when CFG_I2C_BUSES > 1 (imubus.c), a one-bus HAL need not define it. */
int8_t hal_i2c_begin_bus(uint8_t bus, uint8_t addr7, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx);

/* Set the MOSFET PWM duty of an actuator channel, in permyriad (0 = off, 10000 = on);
 * 0 must drive the gate low, not leave a one-count pulse. */
void hal_pwm_set(uint8_t channel, uint16_t duty_permyriad);

/* Bytes are waiting in the transmit ring: turn the transmit interrupt on (it then takes
 * them with uart_isr_tx). Called from the main loop; must return at once. */
void hal_uart_tx_start(void);

/* A board whose host link is CAN (board file [link] transport = "can") also implements
 * hal_can_init and hal_can_tx_start, declared with their contract in canlink.h, in a
 * hal/<family>/can*.c file that only such images contain. */

/* Non-volatile storage: one small block of HAL_NV_BYTES bytes that survives reset and
 * power loss (AVR: EEPROM from address 0; STM32F1: the last 1 KiB flash page; host-sim:
 * memory that sim_reset keeps). Erased bytes read 0xFF. The core keeps its level
 * calibration there (level.h). hal_nv_read copies the first n bytes at once.
 * hal_nv_write begins storing n bytes at the block's start (src must stay valid until
 * hal_nv_poll() no longer returns HAL_NV_BUSY): 0 begun, negative when n > HAL_NV_BYTES or
 * a write is in flight. hal_nv_poll: HAL_NV_BUSY while writing, 0 done, negative failed.
 * A write may take milliseconds (AVR: 3.4 ms per changed byte, one byte per poll, never
 * waiting; STM32: a page erase stalls the CPU for up to 40 ms, so the core writes only when
 * no gait runs). */
#define HAL_NV_BYTES 32u
#define HAL_NV_BUSY 1
void hal_nv_read(uint8_t *dst, uint8_t n);
int8_t hal_nv_write(const uint8_t *src, uint8_t n);
int8_t hal_nv_poll(void);

#endif /* PROLEG_HAL_H */
