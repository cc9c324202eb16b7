/* sim_tca9548a.h - register-level TCA9548A / PCA9548A I2C multiplexers on the simulated buses.
 *
 * Contract. Up to SIM_TCA_MAX devices, each on one simulated bus at a 7-bit address
 * 0x70..0x77 (A2..A0); only attached ones acknowledge. The device has one register, the
 * control register: bit c set = downstream channel c connected (several may be). A write
 * stores the last byte written (TCA9548A datasheet, SCPS207, §8.5.4: "the last byte
 * received is kept"); a read returns the control register for every byte read. Power-on
 * (and the RESET pin): 0x00, every channel disconnected. A channel's devices are on the
 * bus only while its bit is set (hal_sim.c asks sim_tca_enabled before routing).
 */
#ifndef PROLEG_SIM_TCA9548A_H
#define PROLEG_SIM_TCA9548A_H

#include <stdint.h>

#define SIM_TCA_MAX 8u

/* Every multiplexer detached, control registers 0. */
void sim_tca_power_on(void);

/* A multiplexer on bus at addr (0x70..0x77); attaching one twice is harmless. */
void sim_tca_attach(uint8_t bus, uint8_t addr);

/* One I2C transaction addressed to (bus, addr): -1 when no multiplexer is there. */
int sim_tca_transfer(uint8_t bus, uint8_t addr, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx);

/* 1 when the multiplexer at (bus, addr) connects channel ch. */
uint8_t sim_tca_enabled(uint8_t bus, uint8_t addr, uint8_t ch);

/* The control register of the multiplexer at (bus, addr); 0 when there is none. */
uint8_t sim_tca_control(uint8_t bus, uint8_t addr);

/* Control-register writes since power-on, all multiplexers. */
uint32_t sim_tca_writes(void);

#endif /* PROLEG_SIM_TCA9548A_H */
