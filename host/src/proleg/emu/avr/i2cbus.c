/* i2cbus.c - who answers on avr-emu's TWI bus: the MPU-6050 models and TCA9548A multiplexers.
 *
 * Contract. i2cbus_transfer(addr7, …) is one transfer with whatever answers at an address,
 * as twi.c's master puts it on the bus; i2cbus_unwire_all is the power-on (no model wired,
 * no multiplexer). The emu_imu_* ABI below wires model slots and sets what they sense. The
 * start-up times are configuration, kept across resets. Nothing here knows the TWI
 * registers or their timing (twi.c).
 *
 * The devices are the MPU-6050 models (model slot i, wired at an address, directly or
 * behind a TCA9548A channel) and the TCA9548A multiplexers (sim_tca9548a.c, as on
 * host-sim); an address acknowledges when a multiplexer sits there, or a model wired there
 * (directly, or behind a connected channel) that is not faulted "no-ack" and is past its
 * start-up time. Several models that answer at once drive the open-drain bus together: the
 * master reads the AND of their bytes.
 */
#include <string.h>

#include "harness.h"
#include "sim_mpu6050.h"
#include "sim_tca9548a.h"

#define EMU_API __attribute__((visibility("default")))

/* Start-up time of each model slot after power-on: configuration, kept across resets. */
static uint64_t startup_us[SIM_MPU_MAX];

/* Where each model slot sits on the bus: its address, and its multiplexer (0: wired
 * directly) and channel. Configuration, kept across resets. */
static struct {
    uint8_t used, addr, mux, ch;
} wire[SIM_MPU_MAX];

int i2cbus_transfer(uint8_t addr7, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx, uint64_t t_us)
{
    uint8_t tmp[8];
    uint8_t i, j, acked = 0;
    if (sim_tca_transfer(0, addr7, tx, ntx, rx, nrx) == 0) {
        return 0;
    }
    for (i = 0; i < SIM_MPU_MAX; i++) {
        if (!wire[i].used || wire[i].addr != addr7 || emu_now_us() < startup_us[i] ||
            (wire[i].mux && !sim_tca_enabled(0, wire[i].mux, wire[i].ch))) {
            continue; /* elsewhere, still powering up, or its channel is off */
        }
        if (sim_mpu_transfer_slot(i, tx, ntx, acked ? tmp : rx, acked && nrx > sizeof tmp ? sizeof tmp : nrx, t_us) != 0) {
            continue;
        }
        if (acked) {
            for (j = 0; j < nrx && j < sizeof tmp; j++) {
                rx[j] &= tmp[j];
            }
        }
        acked = 1;
    }
    return acked ? 0 : -1;
}

void i2cbus_unwire_all(void)
{
    memset(wire, 0, sizeof wire);
    sim_tca_power_on();
}

static void wire_imu(uint8_t slot, uint8_t addr7, uint8_t mux, uint8_t ch)
{
    if (slot < SIM_MPU_MAX) {
        wire[slot].used = 1;
        wire[slot].addr = addr7;
        wire[slot].mux = mux;
        wire[slot].ch = ch;
        sim_mpu_attach_slot(slot);
        if (mux) {
            sim_tca_attach(0, mux);
        }
    }
}

/* IMU keys: 0x80 | model slot, or the address of an IMU wired directly (host-sim's keys,
 * proleg.firmware.placement.sim_imu_keys). -1 for an unknown key. */
static int imu_slot(uint8_t key)
{
    uint8_t i;
    if (key & 0x80u) {
        return (key & 0x7Fu) < SIM_MPU_MAX && wire[key & 0x7Fu].used ? (int)(key & 0x7Fu) : -1;
    }
    for (i = 0; i < SIM_MPU_MAX; i++) {
        if (wire[i].used && !wire[i].mux && wire[i].addr == key) {
            return i;
        }
    }
    return -1;
}

/* -- the ABI ------------------------------------------------------------------------ */

/* An MPU-6050 wired directly at addr (0x68..0x6F), model slot addr - 0x68. */
EMU_API void emu_imu_attach(uint8_t addr)
{
    if (addr >= SIM_MPU_BASE_ADDR && addr < SIM_MPU_BASE_ADDR + SIM_MPU_MAX) {
        wire_imu((uint8_t)(addr - SIM_MPU_BASE_ADDR), addr, 0, 0);
    }
}

/* Model slot `slot` at addr, behind channel ch of the TCA9548A at mux (0: wired directly);
 * its key for the emu_imu_* calls is 0x80 | slot (or addr when wired directly). */
EMU_API void emu_imu_wire(uint8_t slot, uint8_t addr, uint8_t mux, uint8_t ch)
{
    wire_imu(slot, addr, mux, ch);
}

/* The calls below take an IMU key (see imu_slot); an unknown key is ignored. */
EMU_API void emu_imu_set_truth(uint8_t key, double psi_deg, double dpsi_dps)
{
    int slot = imu_slot(key);
    if (slot >= 0) {
        sim_mpu_set_truth_slot((uint8_t)slot, psi_deg, dpsi_dps);
    }
}

EMU_API void emu_imu_set_fault(uint8_t key, uint8_t mode)
{
    int slot = imu_slot(key);
    if (slot >= 0) {
        sim_mpu_set_fault_slot((uint8_t)slot, mode);
    }
}

EMU_API void emu_imu_set_noise(uint8_t key, double accel_ug_rthz, double gyro_dps_rthz, double accel_offset_mg)
{
    int slot = imu_slot(key);
    if (slot >= 0) {
        sim_mpu_set_noise_slot((uint8_t)slot, accel_ug_rthz, gyro_dps_rthz, accel_offset_mg);
    }
}

EMU_API uint8_t emu_imu_peek_reg(uint8_t key, uint8_t reg)
{
    int slot = imu_slot(key);
    return slot >= 0 ? sim_mpu_peek_slot((uint8_t)slot, reg) : 0xFFu;
}

/* The model NACKs until `us` after each power-on reset. */
EMU_API void emu_imu_set_startup_us(uint8_t key, uint64_t us)
{
    int slot = imu_slot(key);
    if (slot >= 0) {
        startup_us[slot] = us;
    }
}
