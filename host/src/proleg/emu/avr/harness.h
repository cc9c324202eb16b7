/* harness.h - the avr-emu board: an ATmega328P on simavr 1.6 with proleg's peripherals.
 *
 * Contract. One emulated board per loaded copy of the library (the MPU-6050 models of
 * sim_mpu6050.c are file-global, so proleg.emu.avr loads a private copy per board).
 * harness.c owns the simavr core, the run loop, resets and the tick-budget markers;
 * uart.c the UART link to the host, pwm.c the PWM read-out, skips.c the skips simavr
 * runs wrong; twi.c replaces simavr's TWI peripheral with a datasheet model (real SCL
 * timing from TWBR/TWPS, the status codes of ATmega328P datasheet §22.7, TWINT cleared
 * only by writing one) on the bus of i2cbus.c, holding the register-level MPU-6050s.
 * Time is the core's cycle counter since the last power-on reset; nothing depends on
 * wall-clock time, so a seed and a sequence of calls give the same run.
 */
#ifndef PROLEG_EMU_AVR_HARNESS_H
#define PROLEG_EMU_AVR_HARNESS_H

#include <stdint.h>

#include "sim_avr.h"

/* The TWI model's hooks for harness.c. */
void twi_attach(avr_t *avr);                      /* after avr_init: take over the registers */
void twi_reset(void);                             /* power-on state of the peripheral and bus */
uint64_t twi_transactions(void);                  /* START..STOP sequences seen since reset */
uint64_t twi_bus_cycles(void);                    /* cycles the bus was owned since reset */
int twi_bus_owned(void);                          /* a START was sent and no STOP completed yet */
void twi_hold_sda(int held, uint8_t release_clocks); /* a device holds SDA low (kept across MCU resets) */

/* i2cbus.c: the devices on the bus (the emu_imu_* ABI wires them). */
int i2cbus_transfer(uint8_t addr7, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx,
                    uint64_t t_us);              /* one transfer with whatever answers: 0, or -1 (no ACK) */
void i2cbus_unwire_all(void);                     /* power-on: no models, no multiplexers on the bus */

/* uart.c: UART0 and the host's two byte queues. */
void uart_open(uint32_t freq, uint32_t host_baud); /* once, before the first core */
int uart_attach(avr_t *avr);                      /* after avr_init: hook UART0; -1 without one */
void uart_power_on(void);                         /* power-on: queues empty, loss counters cleared */
void uart_mcu_reset(void);                        /* every MCU reset: restart delivery to the receiver */

/* skips.c: the skips simavr 1.6 runs wrong (a skip over a one-word ADIW/SBIW it takes for two). */
#define FLASH_WORDS 16384u /* 32 KB of flash */
extern uint8_t skips_bad[FLASH_WORDS / 8u];       /* bit per word address: a skip run here */
void skips_scan(const avr_t *avr);                /* after the firmware is in flash */
void skips_run(avr_t *avr);                       /* execute the skip at pc (only where skips_at) */
static inline int skips_at(uint32_t pc)           /* the core stands on such a skip */
{
    uint32_t w = (pc >> 1) & (FLASH_WORDS - 1u);
    return (skips_bad[w >> 3] >> (w & 7u)) & 1u;
}

/* harness.c services the other parts use. */
uint64_t emu_now_cycles(void);                    /* cycles since the last power-on reset */
uint64_t emu_now_us(void);
uint64_t emu_power_on_cycle(void);                /* the core's cycle count at the last power-on */
void emu_i2c_bus_changed(int owned);              /* bookkeeping of the I2C share of a tick */
avr_t *emu_core(void);                            /* the current simavr core */

/* A register write simavr handles, wrapped: the new handler calls the saved one. */
typedef struct {
    avr_io_write_t c;
    void *param;
} emu_wrapped_t;
void emu_wrap_write(avr_t *avr, uint16_t reg, emu_wrapped_t *save, avr_io_write_t w);
void emu_call_wrapped(const emu_wrapped_t *w, avr_t *avr, avr_io_addr_t addr, uint8_t v);

/* boot.c: flash and the boot section (bootloader mode; no effect until emu_set_boot_reset). */
void boot_power_off(avr_t *avr);                  /* before a power-on reset drops the core */
void boot_power_on(avr_t *avr);                   /* after the new core loaded the ELF */

#endif /* PROLEG_EMU_AVR_HARNESS_H */
