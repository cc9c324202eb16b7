/* Host unit tests of the simulated board's register-level MPU-6050 model
 * (hal/sim/sim_mpu6050.c) and of the firmware's driver (core/mpu6050.c) against it. */
#include <math.h>
#include <string.h>

#include "fake_hal.h"
#include "mpu6050.h"
#include "sim_mpu6050.h"
#include "unit.h"

#define A 0x68u

static void power_on(uint32_t seed)
{
    fake_hal_reset();
    sim_mpu_power_on(seed);
    sim_mpu_attach(0x68);
    sim_mpu_attach(0x69);
}

static uint8_t rd(uint8_t reg)
{
    uint8_t v = 0xEE;
    sim_mpu_transfer(A, &reg, 1, &v, 1, fake_now_us);
    return v;
}

static void wr(uint8_t reg, uint8_t v)
{
    uint8_t tx[2];
    tx[0] = reg;
    tx[1] = v;
    sim_mpu_transfer(A, tx, 2, 0, 0, fake_now_us);
}

static int16_t be16(const uint8_t *p) { return (int16_t)(uint16_t)((p[0] << 8) | p[1]); }

static void burst(uint8_t out[14])
{
    uint8_t reg = 0x3B;
    sim_mpu_transfer(A, &reg, 1, out, 14, fake_now_us);
}

static void test_who_am_i_reads_0x68_at_both_addresses(void)
{
    uint8_t reg = 0x75, v = 0;
    power_on(1);
    CHECK_EQ(rd(0x75), 0x68);
    CHECK_EQ(sim_mpu_transfer(0x69, &reg, 1, &v, 1, 0), 0);
    CHECK_EQ(v, 0x68);
    wr(0x75, 0x12); /* read-only */
    CHECK_EQ(rd(0x75), 0x68);
}

static void test_unattached_address_does_not_acknowledge(void)
{
    uint8_t reg = 0x75, v = 0;
    power_on(1);
    CHECK_EQ(sim_mpu_transfer(0x6A, &reg, 1, &v, 1, 0), -1);
    CHECK_EQ(sim_mpu_transfer(0x50, &reg, 1, &v, 1, 0), -1);
}

static void test_powers_up_asleep_with_frozen_zero_data(void)
{
    uint8_t b[14];
    unsigned i;
    power_on(1);
    CHECK_EQ(rd(0x6B), 0x40);
    sim_mpu_set_truth(A, 30.0, 10.0);
    fake_now_us = 50000;
    burst(b);
    for (i = 0; i < 14u; i++) {
        CHECK_EQ(b[i], 0);
    }
}

static void test_device_reset_bit_self_clears_and_restores_power_up_registers(void)
{
    power_on(1);
    wr(0x6B, 0x01);
    wr(0x1C, 0x18);
    wr(0x1A, 0x03);
    CHECK_EQ(rd(0x1C), 0x18);
    wr(0x6B, 0x80);
    CHECK_EQ(rd(0x6B), 0x40); /* reset bit reads back 0, asleep again */
    CHECK_EQ(rd(0x1C), 0x00);
    CHECK_EQ(rd(0x1A), 0x00);
    CHECK_EQ(rd(0x75), 0x68);
}

static void test_full_scale_settings_read_back_and_scale_the_output(void)
{
    static const int16_t accel_lsb[4] = {16384, 8192, 4096, 2048};
    static const int16_t gyro_100dps[4] = {13100, 6550, 3275, 1638};
    uint8_t fs, b[14];
    power_on(1);
    sim_mpu_set_noise(A, 0.0, 0.0, 0.0);
    sim_mpu_set_truth(A, 0.0, 100.0);
    wr(0x6B, 0x01);
    for (fs = 0; fs < 4u; fs++) {
        wr(0x1C, (uint8_t)(fs << 3));
        wr(0x1B, (uint8_t)(fs << 3));
        CHECK_EQ(rd(0x1C), fs << 3);
        CHECK_EQ(rd(0x1B), fs << 3);
        fake_now_us += 1000;
        burst(b);
        CHECK_EQ(be16(&b[4]), accel_lsb[fs]);
        CHECK(abs(be16(&b[10]) - gyro_100dps[fs]) <= 1);
    }
}

static void test_burst_read_is_big_endian_accel_temp_gyro(void)
{
    uint8_t b[14];
    power_on(1);
    sim_mpu_set_noise(A, 0.0, 0.0, 0.0);
    sim_mpu_set_truth(A, 30.0, -20.0);
    wr(0x6B, 0x01);
    fake_now_us = 1000;
    burst(b);
    CHECK_EQ(b[0], 0x20); /* ax = 16384 · sin 30° = 8192 = 0x2000 */
    CHECK_EQ(b[1], 0x00);
    CHECK_EQ(be16(&b[2]), 0);
    CHECK_EQ(be16(&b[4]), 14189); /* 16384 · cos 30° */
    CHECK_EQ(b[4], 0x37);
    CHECK_EQ(b[5], 0x6D);
    CHECK_EQ(be16(&b[6]), -3920); /* 25 °C */
    CHECK_EQ(be16(&b[8]), 0);
    CHECK_EQ(be16(&b[10]), -2620); /* -20 °/s at 131 LSB/(°/s) */
    CHECK_EQ(be16(&b[12]), 0);
}

static void test_data_refresh_once_per_sample_period(void)
{
    uint8_t b1[14], b2[14], b3[14];
    power_on(3);
    wr(0x6B, 0x01);
    wr(0x1A, 0x03); /* DLPF on: 1 kHz */
    fake_now_us = 10000;
    burst(b1);
    fake_now_us = 10400;
    burst(b2);
    fake_now_us = 11000;
    burst(b3);
    CHECK(memcmp(b1, b2, 14) == 0);
    CHECK(memcmp(b1, b3, 14) != 0);
}

static void test_noise_follows_density_times_root_bandwidth(void)
{
    /* 400 µg/√Hz at DLPF 3 (44 Hz): σ = 2.65 mg = 43.5 LSB at ±2 g. */
    uint8_t b[14];
    double s = 0.0, s2 = 0.0, mean, sd;
    int i, n = 4000;
    power_on(5);
    wr(0x6B, 0x01);
    wr(0x1A, 0x03);
    for (i = 0; i < n; i++) {
        fake_now_us += 1000;
        burst(b);
        s += be16(&b[0]);
        s2 += (double)be16(&b[0]) * be16(&b[0]);
    }
    mean = s / n;
    sd = sqrt(s2 / n - mean * mean);
    printf("  accel x noise sd %.1f LSB (expected 43.5)\n", sd);
    CHECK(fabs(mean) < 5.0);
    CHECK(sd > 43.5 * 0.9 && sd < 43.5 * 1.1);
}

static void test_same_seed_gives_the_same_samples(void)
{
    uint8_t a[14], b[14];
    power_on(42);
    wr(0x6B, 0x01);
    fake_now_us = 7000;
    burst(a);
    power_on(42);
    wr(0x6B, 0x01);
    fake_now_us = 7000;
    burst(b);
    CHECK(memcmp(a, b, 14) == 0);
    power_on(43);
    wr(0x6B, 0x01);
    fake_now_us = 7000;
    burst(b);
    CHECK(memcmp(a, b, 14) != 0);
}

static void test_faults_no_ack_stuck_and_garbage(void)
{
    uint8_t a[14], b[14], reg = 0x3B;
    power_on(9);
    wr(0x6B, 0x01);
    sim_mpu_set_fault(A, SIM_MPU_NO_ACK);
    CHECK_EQ(sim_mpu_transfer(A, &reg, 1, a, 14, 0), -1);
    sim_mpu_set_fault(A, SIM_MPU_STUCK);
    fake_now_us = 1000;
    burst(a);
    sim_mpu_set_truth(A, 45.0, 0.0);
    fake_now_us = 90000;
    burst(b);
    CHECK(memcmp(a, b, 14) == 0);
    sim_mpu_set_fault(A, SIM_MPU_GARBAGE);
    burst(a);
    burst(b);
    CHECK(memcmp(a, b, 14) != 0);
    sim_mpu_set_fault(A, SIM_MPU_OK);
    CHECK_EQ(rd(0x75), 0x68);
}

/* The driver's start-up steps, one transaction each, as imucheck.c runs them. */
static int8_t drive_init(uint8_t addr)
{
    uint8_t step, tx[2], ntx, nrx, rx = 0;
    int8_t r;
    for (step = 0; step < MPU6050_INIT_STEPS; step++) {
        mpu6050_init_step(step, tx, &ntx, &nrx);
        if (hal_i2c_begin(addr, tx, ntx, &rx, nrx) != 0 || hal_i2c_poll() != 0) {
            return MPU6050_ERR_BUS;
        }
        r = mpu6050_init_check(step, rx);
        if (r != MPU6050_OK) {
            return r;
        }
    }
    return MPU6050_OK;
}

static int8_t drive_read_accel(uint8_t addr, mpu6050_accel_t *out)
{
    uint8_t reg = MPU6050_REG_ACCEL_XOUT_H, b[MPU6050_ACCEL_BYTES];
    if (hal_i2c_begin(addr, &reg, 1, b, MPU6050_ACCEL_BYTES) != 0 || hal_i2c_poll() != 0) {
        return MPU6050_ERR_BUS;
    }
    mpu6050_accel(b, out);
    return MPU6050_OK;
}

static void test_driver_init_wakes_and_configures_the_chip(void)
{
    mpu6050_accel_t acc;
    power_on(11);
    sim_mpu_set_truth(A, 0.0, 0.0);
    CHECK_EQ(drive_init(A), MPU6050_OK);
    CHECK_EQ(sim_mpu_peek(A, 0x6B), 0x01);
    CHECK_EQ(sim_mpu_peek(A, 0x1A), MPU6050_DLPF_CFG);
    CHECK_EQ(sim_mpu_peek(A, 0x1C), MPU6050_AFS_SEL << 3);
    fake_now_us = 2000;
    CHECK_EQ(drive_read_accel(A, &acc), MPU6050_OK);
    CHECK(abs(acc.az - MPU6050_ACCEL_LSB_PER_G) < 200);
    CHECK(abs(acc.ax) < 200);
}

static void test_driver_reports_a_silent_or_wrong_chip(void)
{
    power_on(12);
    sim_mpu_set_fault(A, SIM_MPU_NO_ACK);
    CHECK_EQ(drive_init(A), MPU6050_ERR_BUS);
    sim_mpu_set_fault(A, SIM_MPU_GARBAGE);
    CHECK_EQ(drive_init(A), MPU6050_ERR_IDENTITY);
    CHECK_EQ(drive_init(0x6A), MPU6050_ERR_BUS);
}

int main(void)
{
    RUN(test_who_am_i_reads_0x68_at_both_addresses);
    RUN(test_unattached_address_does_not_acknowledge);
    RUN(test_powers_up_asleep_with_frozen_zero_data);
    RUN(test_device_reset_bit_self_clears_and_restores_power_up_registers);
    RUN(test_full_scale_settings_read_back_and_scale_the_output);
    RUN(test_burst_read_is_big_endian_accel_temp_gyro);
    RUN(test_data_refresh_once_per_sample_period);
    RUN(test_noise_follows_density_times_root_bandwidth);
    RUN(test_same_seed_gives_the_same_samples);
    RUN(test_faults_no_ack_stuck_and_garbage);
    RUN(test_driver_init_wakes_and_configures_the_chip);
    RUN(test_driver_reports_a_silent_or_wrong_chip);
    return UNIT_EXIT();
}
