/* hal_template.c - hal.h for a new MCU family: every function the core needs, stubbed.
 *
 * Copy firmware_templates/hal/template/ to firmware_templates/hal/<family>/, rename this
 * file hal_<family>.c, and fill in each function below; its comment says what it must
 * do and how long it may take. Then write a board file (boards/<board>.toml) that names
 * the family. docs/adding-a-board.md walks through it.
 *
 * What the core already does, so a HAL does not: main() and the tick loop (core/main.c,
 * paced on hal_micros; leave it out with [build] main_loop = false when a host program
 * drives app_init/app_tick instead), the UART byte rings (core/uart.h), the protocol,
 * the safety envelope. Everything board-specific the renderer knows comes from the
 * board file and this folder's family.toml, as CFG_* macros in robot_config.h:
 *   CFG_CLOCK_HZ, CFG_TICK_US, CFG_I2C_HZ, CFG_PWM_CHANNELS, CFG_PWM_MAP (one entry per
 *   channel, from family.toml), CFG_PWM_HZ, CFG_UART_BAUD, CFG_UART_RX_BYTES/TX_BYTES.
 * Other files of this folder (.c, .h, .S, .ld) are copied into the project's hal/:
 * startup code, a linker script (an .ld file is passed to the linker), register headers.
 */
#include <stdint.h>

#include "hal.h"
#include "robot_config.h"
#include "uart.h"

/* Your CFG_PWM_MAP entries, one per channel (family.toml's [pwm] pins). With
 * pins = "any" each entry is the channel number. */
static const uint8_t pwm_map[CFG_PWM_CHANNELS] = CFG_PWM_MAP;

/* Called once, first, with interrupts as the reset left them. Must: start the clocks;
 * start the microsecond counter; set up I2C master at CFG_I2C_HZ on the IMU bus; set
 * every PWM channel of CFG_PWM_MAP to CFG_PWM_HZ with its output driven low (coils off)
 * before anything else can turn it on; set up the UART at CFG_UART_BAUD, 8N1, with its
 * receive interrupt on (each byte to uart_isr_rx); enable interrupts. May take as long
 * as the clocks need to settle (no tick runs yet). */
void hal_init(void)
{
}

/* Microseconds since hal_init, free-running, wrapping at 2^32. Must be monotonic across
 * the counter's own overflow (read the overflow count and the counter consistently) and
 * callable from the main loop at any time; a few microseconds at most. The core paces
 * the control tick on it and bounds every wait with it. */
uint32_t hal_micros(void)
{
    return 0;
}

/* Begin one I2C transaction with the 7-bit address addr7 in the background: write ntx
 * bytes from tx, then (with a repeated start when both are non-zero) read nrx bytes
 * into rx, NACKing the last one; tx and rx stay valid until hal_i2c_poll() is no longer
 * HAL_I2C_BUSY. Return 0 when begun, -1 if the previous one is still in flight. Best
 * done from the I2C interrupt (one byte per interrupt); a board may also run the whole
 * transaction here if it takes a few tens of µs at most. */
int8_t hal_i2c_begin(uint8_t addr7, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx)
{
    (void)addr7;
    (void)tx;
    (void)ntx;
    (void)rx;
    (void)nrx;
    return -1;
}

/* HAL_I2C_BUSY while the transaction is in flight, 0 when it completed, negative on NACK,
 * arbitration loss or bus error. Never waits. Past HAL_I2C_DEADLINE_US since the begin,
 * abort it, leave the bus usable (9 SCL clocks if a slave holds SDA low, a STOP) and
 * return negative. */
int8_t hal_i2c_poll(void)
{
    return -1;
}

/* hal_i2c_begin on I2C bus `bus` (its index in the board file's [[i2c.bus]] list; bus 0
 * is hal_i2c_begin's): only for an MCU with a second I2C peripheral. The core calls it only
 * when a robot's IMUs use bus 1 or above (CFG_I2C_BUSES > 1); one transaction at a time over
 * all buses, and hal_i2c_poll() reports the last one begun. Return -1 for a bus you lack
 * or while a transaction is in flight. */
int8_t hal_i2c_begin_bus(uint8_t bus, uint8_t addr7, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx)
{
    (void)bus;
    (void)addr7;
    (void)tx;
    (void)ntx;
    (void)rx;
    (void)nrx;
    return -1;
}

/* Set channel's duty in permyriad (0..10000) at once (takes effect within one PWM
 * period). 0 must drive the gate low with no pulse at all, 10000 high; ignore a channel
 * >= CFG_PWM_CHANNELS. Called from the main loop every tick and on E-stop: a few
 * microseconds, no waiting. */
void hal_pwm_set(uint8_t channel, uint16_t duty_permyriad)
{
    if (channel >= CFG_PWM_CHANNELS) {
        return;
    }
    (void)pwm_map[channel];
    (void)duty_permyriad;
}

/* Bytes are waiting in the transmit ring. Must return at once: turn the UART's
 * transmit-empty interrupt on. That interrupt handler then sends uart_isr_tx() byte by
 * byte and turns itself off when it returns -1. (A board with no interrupt can instead
 * drain uart_isr_tx() here, if the bytes leave without waiting.) */
void hal_uart_tx_start(void)
{
}

/* Read the reset flags in hal_init (then clear them so the next reset reports its own)
 * and return the cause as HAL_RESET_*; HAL_RESET_UNKNOWN if the MCU cannot tell. Anything but
 * HAL_RESET_POWER_ON lets the envelope keep what the coils spent before the reset, from RAM
 * the start-up code leaves alone: an AVR or Cortex-M link script must place the `.noinit`
 * section in RAM after .bss, not zeroed (core/initzero.h NOINIT; docs/safety.md, "A reset"). */
uint8_t hal_reset_cause(void)
{
    return HAL_RESET_UNKNOWN;
}

/* Start the hardware watchdog in hal_init (a period of a few ticks, tens of ms); this
 * reloads it. The core calls it once after every completed tick, nowhere else. */
void hal_watchdog_feed(void)
{
}

/* One store to a register or pin with no other effect: 1 when a tick's work starts, 0
 * when it ends (a debug pin gives a logic probe the tick budget). */
void hal_tick_mark(uint8_t busy)
{
    (void)busy;
}

/* Interrupt handlers (names and attributes are the MCU's): the UART's receive interrupt
 * passes every byte to uart_isr_rx(byte); its transmit-empty interrupt does
 *     int b = uart_isr_tx(); if (b < 0) { transmit interrupt off; } else { send (uint8_t)b; }
 * the timer overflow interrupt, if hal_micros needs one, counts overflows. */

/* Non-volatile block (hal.h): HAL_NV_BYTES bytes that survive reset and power loss, erased
 * = 0xFF. An EEPROM: write one changed byte per hal_nv_poll, never waiting; a flash page:
 * erase and program it in hal_nv_write (the core writes only while no gait runs). This
 * stub has none: reads are "erased" and writes fail, so the core reports no calibration. */
void hal_nv_read(uint8_t *dst, uint8_t n)
{
    uint8_t i;
    for (i = 0; i < n; i++) {
        dst[i] = 0xFFu;
    }
}

int8_t hal_nv_write(const uint8_t *src, uint8_t n)
{
    (void)src;
    (void)n;
    return -1;
}

int8_t hal_nv_poll(void)
{
    return 0;
}
