/* imubus.h - which bus, multiplexer channel and address each limb's IMU sits at.
 *
 * Contract. imubus_select(limb) makes limb's IMU the one imubus_write_read() talks to:
 * it picks the limb's bus and, when the IMU sits behind a TCA9548A/PCA9548A multiplexer
 * (CFG_LIMB_IMU_MUX != 0), writes the multiplexer's control byte (1 << channel) only when
 * that bus's enabled channel changes; each such write is one short blocking I2C transfer
 * between ticks, before the limb's own transaction (counted by imubus_switches()). A failed select forgets the bus's channel (the
 * next select writes it again) and makes imubus_write_read() fail until the next good
 * select, so a limb never reads another limb's IMU. Tables come from robot_config.h
 * (CFG_LIMB_IMU_BUS/_MUX/_CHANNEL); bus 0 is hal_i2c_write_read's bus, others go through
 * hal_i2c_write_read_bus (only compiled in when CFG_I2C_BUSES > 1).
 */
#ifndef PROLEG_IMUBUS_H
#define PROLEG_IMUBUS_H

#include <stdint.h>

#include "robot_config.h"

#if CFG_I2C_BUSES > 4
#error "at most 4 I2C buses"
#endif

/* Forget every bus's channel (power-on: the multiplexers have every channel off);
 * the zero-initialised state is the same, so a transfer before any select goes to bus 0. */
void imubus_init(void);

/* Route the next transfers to limb's IMU; 0, or negative when the multiplexer did not ACK. */
int8_t imubus_select(uint8_t limb);

/* One transfer on the selected limb's bus (hal.h semantics); negative after a failed select. */
int imubus_write_read(uint8_t addr7, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx);

/* 1 when the selected limb's IMU is on a bus other than bus 0 (hal_i2c_begin's bus). */
uint8_t imubus_on_second_bus(void);

/* Control-byte writes since imubus_init (wraps). */
uint32_t imubus_switches(void);

#endif /* PROLEG_IMUBUS_H */
