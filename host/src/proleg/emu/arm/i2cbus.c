/* i2cbus.c - who answers on arm-emu's I2C buses (I2C1 = bus 0, I2C2 = bus 1).
 *
 * The devices are the shared register-level models of every simulated board: MPU-6050s
 * (sim_mpu6050.c, by model slot) and TCA9548A/PCA9548A multiplexers (sim_tca9548a.c, the
 * model host-sim and avr-emu use too). Each model slot is wired to a bus at an address,
 * directly or behind one channel of a multiplexer on that bus (emu_i2c_wire).
 *
 * An address acknowledges when a multiplexer sits there, or a model wired there directly
 * or behind an active channel that is not faulted "no-ack". Several models that answer at
 * once (the same address on two active channels) drive the open-drain bus together: the
 * master reads the AND of their bytes. This is the routing of hal_sim.c and avr-emu's
 * i2cbus.c, with one datasheet detail more that only a register-level master can see
 * (TI TCA9548A, SCPS207F §8.5.4): the control register takes the last byte written at
 * once (a read returns it), but "when a channel is selected, the channel becomes active
 * after a stop condition has been placed on the I2C bus". emu_i2c_stop(bus) is that STOP;
 * until then the channels of the previous control value stay connected. Power-on (and
 * the device's RESET pin, which the bluepill does not drive): 0x00, no channel.
 */
#include <stdint.h>
#include <string.h>

#include "sim_mpu6050.h"
#include "sim_tca9548a.h"

#define BUSES 4u

static struct {
    uint8_t used, bus, addr, mux, ch;
} wire[SIM_MPU_MAX];

/* Per model slot: no ACK before this many µs after power-on (an IMU that answers late,
 * MPU-6050 start-up time: mpu6050.h). Kept across unwire/power-on, as avr-emu's i2cbus.c. */
static uint64_t startup_us[SIM_MPU_MAX];

/* The connected channels of each multiplexer, as of the last STOP on its bus. */
static struct {
    uint8_t used, bus, addr, active;
} mux[SIM_TCA_MAX];

void emu_i2c_add_mux(uint8_t bus, uint8_t addr7);

static uint8_t active(uint8_t bus, uint8_t addr, uint8_t ch)
{
    uint8_t i;
    for (i = 0; i < SIM_TCA_MAX; i++) {
        if (mux[i].used && mux[i].bus == bus && mux[i].addr == addr) {
            return (uint8_t)((mux[i].active >> ch) & 1u);
        }
    }
    return 0;
}

/* Every slot unwired, every multiplexer detached and at its power-on value. */
void emu_i2c_unwire(void)
{
    memset(wire, 0, sizeof wire);
    memset(mux, 0, sizeof mux);
    sim_tca_power_on();
}

/* Model slot `slot` on `bus` at addr7, behind channel ch of the multiplexer at mux_addr
 * (0: wired directly). The model is attached (sim_mpu_attach_slot); call after
 * sim_mpu_power_on. */
void emu_i2c_wire(uint8_t slot, uint8_t bus, uint8_t addr7, uint8_t mux_addr, uint8_t ch)
{
    if (slot >= SIM_MPU_MAX || bus >= BUSES || ch > 7u) {
        return;
    }
    wire[slot].used = 1;
    wire[slot].bus = bus;
    wire[slot].addr = addr7;
    wire[slot].mux = mux_addr;
    wire[slot].ch = ch;
    sim_mpu_attach_slot(slot);
    if (mux_addr != 0u) {
        emu_i2c_add_mux(bus, mux_addr);
    }
}

/* A multiplexer on `bus` at addr7 with no IMU behind it (a test's bus). */
void emu_i2c_add_mux(uint8_t bus, uint8_t addr7)
{
    uint8_t i;
    if (bus >= BUSES || addr7 < 0x70u || addr7 > 0x77u) {
        return;
    }
    sim_tca_attach(bus, addr7);
    for (i = 0; i < SIM_TCA_MAX; i++) {
        if (mux[i].used && mux[i].bus == bus && mux[i].addr == addr7) {
            return;
        }
    }
    for (i = 0; i < SIM_TCA_MAX; i++) {
        if (!mux[i].used) {
            mux[i].used = 1;
            mux[i].bus = bus;
            mux[i].addr = addr7;
            mux[i].active = 0;
            return;
        }
    }
}

/* One transaction with whatever answers at addr7 on bus: 0, or -1 when nothing acknowledges. */
int emu_i2c_transfer(uint8_t bus, uint8_t addr7, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx, uint64_t t_us)
{
    uint8_t tmp[16];
    uint8_t i, j, n, acked = 0;
    if (sim_tca_transfer(bus, addr7, tx, ntx, rx, nrx) == 0) {
        return 0;
    }
    for (i = 0; i < SIM_MPU_MAX; i++) {
        if (!wire[i].used || wire[i].bus != bus || wire[i].addr != addr7 || t_us < startup_us[i] ||
            (wire[i].mux && !active(bus, wire[i].mux, wire[i].ch))) {
            continue; /* elsewhere, still powering up, or its channel is not connected */
        }
        n = acked && nrx > sizeof tmp ? (uint8_t)sizeof tmp : nrx;
        if (sim_mpu_transfer_slot(i, tx, ntx, acked ? tmp : rx, n, t_us) != 0) {
            continue;
        }
        if (acked) {
            for (j = 0; j < n; j++) {
                rx[j] &= tmp[j];
            }
        }
        acked = 1;
    }
    return acked ? 0 : -1;
}

/* A STOP condition on bus: each multiplexer there connects what its control register says. */
void emu_i2c_stop(uint8_t bus)
{
    uint8_t i;
    for (i = 0; i < SIM_TCA_MAX; i++) {
        if (mux[i].used && mux[i].bus == bus) {
            mux[i].active = sim_tca_control(bus, mux[i].addr);
        }
    }
}

/* The connected channels of the multiplexer at (bus, addr7): a probe for tests. */
uint8_t emu_i2c_mux_active(uint8_t bus, uint8_t addr7)
{
    uint8_t i;
    for (i = 0; i < SIM_TCA_MAX; i++) {
        if (mux[i].used && mux[i].bus == bus && mux[i].addr == addr7) {
            return mux[i].active;
        }
    }
    return 0;
}

/* Model slot `slot` acknowledges only from `us` after power-on (0: at once). */
void emu_i2c_set_startup_us(uint8_t slot, uint64_t us)
{
    if (slot < SIM_MPU_MAX) {
        startup_us[slot] = us;
    }
}
