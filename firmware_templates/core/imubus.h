/* imubus.h - which bus, multiplexer channel and address each limb's IMU sits at, and its
 * transactions in the background.
 *
 * Contract. imubus_begin(limb, ...) starts limb's transaction on limb's bus and returns at
 * once; imubus_poll() moves it on and reports it (hal.h's hal_i2c_poll semantics). When the
 * IMU sits behind a TCA9548A/PCA9548A multiplexer (CFG_LIMB_IMU_MUX != 0) and that bus's
 * enabled channel is not the limb's, the multiplexer's control byte (1 << channel) goes out
 * first, itself a background transaction, and the IMU's transaction begins from
 * imubus_poll() once it is ACKed (counted by imubus_switches()). A select that fails
 * forgets the bus's channel (the next begin writes it again) and ends the transaction
 * with -1, so a limb never reads another limb's IMU. Tables come from robot_config.h
 * (CFG_LIMB_IMU_BUS/_MUX/_CHANNEL); bus 0 is hal_i2c_begin's, others go through
 * hal_i2c_begin_bus (only compiled in when CFG_I2C_BUSES > 1). One transaction at a time.
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

/* Begin limb's transaction: write ntx bytes from tx to addr7, then read nrx into rx (the
 * buffers stay valid until imubus_poll() no longer returns HAL_I2C_BUSY). 0 when begun,
 * negative when a transaction is still in flight or the HAL refused it. */
int8_t imubus_begin(uint8_t limb, uint8_t addr7, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx);

/* HAL_I2C_BUSY while the select or the transaction is in flight, then 0 or negative (the
 * last one begun, as hal_i2c_poll). Never waits. */
int8_t imubus_poll(void);

/* Control-byte writes since imubus_init (wraps). */
uint32_t imubus_switches(void);

#endif /* PROLEG_IMUBUS_H */
