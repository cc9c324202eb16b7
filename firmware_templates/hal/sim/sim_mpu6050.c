/* sim_mpu6050.c - see sim_mpu6050.h. Host code (doubles, libm) for the simulated board only. */
#include "sim_mpu6050.h"

#include <math.h>
#include <string.h>

#define REG_SMPLRT_DIV 0x19u
#define REG_CONFIG 0x1Au
#define REG_GYRO_CONFIG 0x1Bu
#define REG_ACCEL_CONFIG 0x1Cu
#define REG_DATA_FIRST 0x3Bu
#define REG_DATA_LAST 0x48u
#define REG_PWR_MGMT_1 0x6Bu
#define REG_WHO_AM_I 0x75u
#define PWR_RESET 0x80u
#define PWR_SLEEP 0x40u
#define PI_D 3.14159265358979323846

/* Noise bandwidth (Hz) per DLPF_CFG, accelerometer and gyro (datasheet table). */
static const double accel_bw[8] = {260.0, 184.0, 94.0, 44.0, 21.0, 10.0, 5.0, 260.0};
static const double gyro_bw[8] = {256.0, 188.0, 98.0, 42.0, 20.0, 10.0, 5.0, 256.0};

typedef struct {
    uint8_t present;
    uint8_t fault;
    uint8_t ptr;
    uint8_t regs[128];
    double psi_deg, dpsi_dps;
    double accel_ug_rthz, gyro_dps_rthz, offset_mg;
    uint64_t rng;
    uint64_t sample_index; /* virtual-time sample the data registers hold, +1 (0 = none) */
} mpu_t;

static mpu_t devs[SIM_MPU_MAX];

static mpu_t *slot_dev(uint8_t slot)
{
    return slot < SIM_MPU_MAX ? &devs[slot] : 0;
}

static mpu_t *dev(uint8_t addr)
{
    if (addr < SIM_MPU_BASE_ADDR || addr >= SIM_MPU_BASE_ADDR + SIM_MPU_MAX) {
        return 0;
    }
    return slot_dev((uint8_t)(addr - SIM_MPU_BASE_ADDR));
}

static uint64_t splitmix(uint64_t *x)
{
    uint64_t z = (*x += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

static double uniform(mpu_t *d) /* (0, 1] */
{
    return ((double)(splitmix(&d->rng) >> 11) + 1.0) / 9007199254740992.0;
}

static double gauss(mpu_t *d)
{
    double u1 = uniform(d), u2 = uniform(d);
    return sqrt(-2.0 * log(u1)) * cos(2.0 * PI_D * u2);
}

static void power_up_registers(mpu_t *d)
{
    memset(d->regs, 0, sizeof d->regs);
    d->regs[REG_PWR_MGMT_1] = PWR_SLEEP;
    d->regs[REG_WHO_AM_I] = 0x68u;
    d->ptr = 0;
    d->sample_index = 0;
}

void sim_mpu_power_on(uint32_t seed)
{
    uint8_t i;
    for (i = 0; i < SIM_MPU_MAX; i++) {
        mpu_t *d = &devs[i];
        memset(d, 0, sizeof *d);
        power_up_registers(d);
        d->accel_ug_rthz = 400.0;
        d->gyro_dps_rthz = 0.005;
        d->rng = ((uint64_t)seed << 8) ^ (uint64_t)(SIM_MPU_BASE_ADDR + i) ^ 0x5EEDull;
        (void)splitmix(&d->rng);
    }
}

static void attach(mpu_t *d)
{
    if (d) {
        d->present = 1;
    }
}

static void put16(uint8_t *p, double v)
{
    long r = lround(v);
    int16_t s;
    if (r > 32767) {
        r = 32767;
    } else if (r < -32768) {
        r = -32768;
    }
    s = (int16_t)r;
    p[0] = (uint8_t)((uint16_t)s >> 8);
    p[1] = (uint8_t)((uint16_t)s & 0xFFu);
}

/* Refresh the data registers when virtual time has moved to a new sample. */
static void sample(mpu_t *d, uint64_t t_us)
{
    uint8_t dlpf = d->regs[REG_CONFIG] & 7u;
    uint64_t base_us = (dlpf == 0u || dlpf == 7u) ? 125u : 1000u; /* gyro output rate 8 or 1 kHz */
    uint64_t period = base_us * (1u + d->regs[REG_SMPLRT_DIV]);
    uint64_t idx = t_us / period + 1u;
    double lsb_g = 16384.0 / (double)(1u << ((d->regs[REG_ACCEL_CONFIG] >> 3) & 3u));
    double lsb_dps = 131.0 / (double)(1u << ((d->regs[REG_GYRO_CONFIG] >> 3) & 3u));
    double sa = d->accel_ug_rthz * 1e-6 * sqrt(accel_bw[dlpf]);
    double sg = d->gyro_dps_rthz * sqrt(gyro_bw[dlpf]);
    double off = d->offset_mg * 1e-3;
    double psi = d->psi_deg * PI_D / 180.0;
    uint8_t *r = &d->regs[REG_DATA_FIRST];
    if (d->regs[REG_PWR_MGMT_1] & PWR_SLEEP || d->fault == SIM_MPU_STUCK || idx == d->sample_index) {
        return;
    }
    d->sample_index = idx;
    put16(&r[0], (sin(psi) + off + sa * gauss(d)) * lsb_g);
    put16(&r[2], (off + sa * gauss(d)) * lsb_g);
    put16(&r[4], (cos(psi) + off + sa * gauss(d)) * lsb_g);
    put16(&r[6], (25.0 - 36.53) * 340.0);
    put16(&r[8], sg * gauss(d) * lsb_dps);
    put16(&r[10], (d->dpsi_dps + sg * gauss(d)) * lsb_dps);
    put16(&r[12], sg * gauss(d) * lsb_dps);
}

static void write_reg(mpu_t *d, uint8_t reg, uint8_t v)
{
    if (reg >= 128u || reg == REG_WHO_AM_I || (reg >= REG_DATA_FIRST && reg <= 0x60u)) {
        return; /* read-only or absent */
    }
    if (reg == REG_PWR_MGMT_1 && (v & PWR_RESET)) {
        power_up_registers(d); /* DEVICE_RESET: reads back 0 once done */
        return;
    }
    d->regs[reg] = v;
}

static int transfer(mpu_t *d, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx, uint64_t t_us)
{
    uint8_t i;
    if (!d || !d->present || d->fault == SIM_MPU_NO_ACK) {
        return -1;
    }
    if (ntx > 0u) {
        d->ptr = tx[0];
        for (i = 1; i < ntx; i++) {
            write_reg(d, d->ptr, tx[i]);
            d->ptr = (uint8_t)((d->ptr + 1u) & 0x7Fu);
        }
    }
    if (nrx > 0u) {
        sample(d, t_us);
        for (i = 0; i < nrx; i++) {
            rx[i] = d->fault == SIM_MPU_GARBAGE ? (uint8_t)splitmix(&d->rng) : d->regs[d->ptr & 0x7Fu];
            d->ptr = (uint8_t)((d->ptr + 1u) & 0x7Fu);
        }
    }
    return 0;
}

static void set_truth(mpu_t *d, double psi_deg, double dpsi_dps)
{
    if (d) {
        d->psi_deg = psi_deg;
        d->dpsi_dps = dpsi_dps;
    }
}

static void set_fault(mpu_t *d, uint8_t mode)
{
    if (d && mode <= SIM_MPU_GARBAGE) {
        d->fault = mode;
    }
}

static void set_noise(mpu_t *d, double accel_ug_rthz, double gyro_dps_rthz, double accel_offset_mg)
{
    if (d) {
        d->accel_ug_rthz = accel_ug_rthz < 0.0 ? 0.0 : accel_ug_rthz;
        d->gyro_dps_rthz = gyro_dps_rthz < 0.0 ? 0.0 : gyro_dps_rthz;
        d->offset_mg = accel_offset_mg;
    }
}

static uint8_t peek(const mpu_t *d, uint8_t reg)
{
    return (d && reg < 128u) ? d->regs[reg] : 0u;
}

/* ---- by address (one bus, no multiplexer) and by slot ---- */

void sim_mpu_attach(uint8_t addr) { attach(dev(addr)); }
void sim_mpu_attach_slot(uint8_t slot) { attach(slot_dev(slot)); }

int sim_mpu_transfer(uint8_t addr, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx, uint64_t t_us)
{
    return transfer(dev(addr), tx, ntx, rx, nrx, t_us);
}

int sim_mpu_transfer_slot(uint8_t slot, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx, uint64_t t_us)
{
    return transfer(slot_dev(slot), tx, ntx, rx, nrx, t_us);
}

void sim_mpu_set_truth(uint8_t addr, double psi_deg, double dpsi_dps) { set_truth(dev(addr), psi_deg, dpsi_dps); }
void sim_mpu_set_truth_slot(uint8_t slot, double psi_deg, double dpsi_dps) { set_truth(slot_dev(slot), psi_deg, dpsi_dps); }
void sim_mpu_set_fault(uint8_t addr, uint8_t mode) { set_fault(dev(addr), mode); }
void sim_mpu_set_fault_slot(uint8_t slot, uint8_t mode) { set_fault(slot_dev(slot), mode); }

void sim_mpu_set_noise(uint8_t addr, double accel_ug_rthz, double gyro_dps_rthz, double accel_offset_mg)
{
    set_noise(dev(addr), accel_ug_rthz, gyro_dps_rthz, accel_offset_mg);
}

void sim_mpu_set_noise_slot(uint8_t slot, double accel_ug_rthz, double gyro_dps_rthz, double accel_offset_mg)
{
    set_noise(slot_dev(slot), accel_ug_rthz, gyro_dps_rthz, accel_offset_mg);
}

uint8_t sim_mpu_peek(uint8_t addr, uint8_t reg) { return peek(dev(addr), reg); }
uint8_t sim_mpu_peek_slot(uint8_t slot, uint8_t reg) { return peek(slot_dev(slot), reg); }
