/* harness.h - the avr-emu board: an ATmega328P on simavr 1.6 with proleg's peripherals.
 *
 * Contract. One emulated board per loaded copy of the library (the MPU-6050 models of
 * sim_mpu6050.c are file-global, so proleg.emu.avr loads a private copy per board).
 * harness.c owns the simavr core, the run loop, the UART link, the PWM read-out and the
 * tick-budget markers; twi.c replaces simavr's TWI peripheral with a datasheet model
 * (real SCL timing from TWBR/TWPS, the status codes of ATmega328P datasheet §22.7,
 * TWINT cleared only by writing one) on a bus holding the register-level MPU-6050s.
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
void twi_set_startup_us(uint8_t slot, uint64_t us); /* model slot NACKs until this time after reset */
void twi_wire_imu(uint8_t slot, uint8_t addr7, uint8_t mux, uint8_t ch); /* model slot on the bus (mux 0: direct) */
void twi_unwire_all(void);                        /* power-on: no models, no multiplexers on the bus */
int twi_imu_slot(uint8_t key);                    /* slot of an IMU key (0x80 | slot, or a direct address); -1 */
void twi_hold_sda(int held, uint8_t release_clocks); /* a device holds SDA low (kept across MCU resets) */

/* harness.c services the TWI model uses. */
uint64_t emu_now_cycles(void);                    /* cycles since the last power-on reset */
uint64_t emu_now_us(void);
void emu_i2c_bus_changed(int owned);              /* bookkeeping of the I2C share of a tick */
avr_t *emu_core(void);                            /* the current simavr core */

/* boot.c: flash and the boot section (bootloader mode; no effect until emu_set_boot_reset). */
void boot_power_off(avr_t *avr);                  /* before a power-on reset drops the core */
void boot_power_on(avr_t *avr);                   /* after the new core loaded the ELF */

#endif /* PROLEG_EMU_AVR_HARNESS_H */
