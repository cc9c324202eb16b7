/* sim_mpu6050.h - register-level MPU-6050 models on the simulated I2C bus.
 *
 * Contract. Up to SIM_MPU_MAX devices at 7-bit addresses 0x68..0x6F; only attached
 * addresses acknowledge. Each model behaves like the datasheet for the registers proleg
 * (or a careless driver) touches: WHO_AM_I 0x75 = 0x68 and read-only; power-up asleep
 * (PWR_MGMT_1 = 0x40: data registers frozen, zero after power-up); DEVICE_RESET
 * (PWR_MGMT_1 bit 7) restores the power-up registers and reads back 0; SMPLRT_DIV,
 * CONFIG (DLPF), GYRO_CONFIG and ACCEL_CONFIG read back what was written and set the
 * sample rate, noise bandwidth and full scale; 0x3B..0x48 hold accel xyz, temperature,
 * gyro xyz, big-endian, refreshed once per sample period of virtual time; reads and
 * writes auto-increment the register pointer. The truth is ψ and dψ/dt: the
 * accelerometer reads g·(sin ψ, 0, cos ψ) + offset + white noise, gyro y reads dψ/dt +
 * noise, from a seeded PRNG per device (deterministic for a seed, whatever the order in
 * which devices are read). Faults: no-ack, stuck (data frozen), garbage (random bytes).
 */
#ifndef PROLEG_SIM_MPU6050_H
#define PROLEG_SIM_MPU6050_H

#include <stdint.h>

#define SIM_MPU_BASE_ADDR 0x68u
#define SIM_MPU_MAX 8u

#define SIM_MPU_OK 0u
#define SIM_MPU_NO_ACK 1u
#define SIM_MPU_STUCK 2u
#define SIM_MPU_GARBAGE 3u

/* Power every model off and on again: power-up registers, truth ψ = 0, default noise
 * (400 µg/√Hz, 0.005 °/s/√Hz, no offset), no fault, detached. */
void sim_mpu_power_on(uint32_t seed);

/* Put a device on the bus at addr (0x68..0x6F). */
void sim_mpu_attach(uint8_t addr);

/* One I2C transaction at virtual time t_us: write ntx bytes (first = register pointer),
 * then read nrx bytes. Returns 0, or -1 when no device acknowledges. */
int sim_mpu_transfer(uint8_t addr, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx, uint64_t t_us);

void sim_mpu_set_truth(uint8_t addr, double psi_deg, double dpsi_dps);
void sim_mpu_set_fault(uint8_t addr, uint8_t mode);
void sim_mpu_set_noise(uint8_t addr, double accel_ug_rthz, double gyro_dps_rthz, double accel_offset_mg);
uint8_t sim_mpu_peek(uint8_t addr, uint8_t reg);

/* The same by device slot 0..SIM_MPU_MAX-1 instead of address (slot i is the device
 * that sim_mpu_attach(SIM_MPU_BASE_ADDR + i) attaches): for buses where several devices
 * share one address behind a multiplexer (hal_sim.c routes transfers to slots). */
void sim_mpu_attach_slot(uint8_t slot);
int sim_mpu_transfer_slot(uint8_t slot, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx, uint64_t t_us);
void sim_mpu_set_truth_slot(uint8_t slot, double psi_deg, double dpsi_dps);
void sim_mpu_set_fault_slot(uint8_t slot, uint8_t mode);
void sim_mpu_set_noise_slot(uint8_t slot, double accel_ug_rthz, double gyro_dps_rthz, double accel_offset_mg);
uint8_t sim_mpu_peek_slot(uint8_t slot, uint8_t reg);

#endif /* PROLEG_SIM_MPU6050_H */
