/* test_imucheck.c - core/imucheck.c's background IMU reads against a scripted bus.
 *
 * The HAL here answers every transaction from the register-level MPU-6050 models
 * (hal/sim/sim_mpu6050.c) at once, but reports it HAL_I2C_BUSY for `busy_polls` polls
 * first, like a real bus. A "period" is one tick (imucheck_read) and `idle` calls of
 * imucheck_service (the main loop's idle wait); how many transactions fit in a period is
 * then set by `idle` and `busy_polls`, and so is where in a transaction the tick falls.
 * The ψ classifier and the fault latch are stubbed: the test sees every sample the tick
 * took (psi_update) and every fault raised. Limbs 0 and 1 at 0x68 and 0x69.
 */
#include <string.h>

#include "fault.h"
#include "hal.h"
#include "imucheck.h"
#include "level.h"
#include "proto.h"
#include "psi.h"
#include "seq.h"
#include "sim_mpu6050.h"
#include "unit.h"

#define TICK_US 1000u

static uint64_t now_us;
static int busy_polls = 3; /* a transaction the IMU answers */
static int nack_polls = 3;  /* one it does not: shorter on a real bus (the address byte only) */
static int busy_left = -1; /* <0: nothing begun */
static int8_t result;
static unsigned begun[2];  /* transactions begun per limb */
static unsigned samples[2]; /* samples the tick took per limb */
static unsigned faults;
static uint8_t fault_code[8];
static uint16_t fault_limb[8];

uint32_t hal_micros(void)
{
    return (uint32_t)now_us;
}

int8_t hal_i2c_begin(uint8_t addr7, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx)
{
    if (busy_left >= 0) {
        return -1; /* one transaction at a time: imucheck must never begin a second */
    }
    if (addr7 == 0x68 || addr7 == 0x69) {
        begun[addr7 - 0x68]++;
    }
    result = sim_mpu_transfer(addr7, tx, ntx, rx, nrx, now_us) == 0 ? 0 : -1;
    busy_left = result == 0 ? busy_polls : nack_polls;
    return 0;
}

int8_t hal_i2c_poll(void)
{
    if (busy_left > 0) {
        busy_left--;
        return HAL_I2C_BUSY;
    }
    if (busy_left == 0) {
        busy_left = -1;
    }
    return result;
}

void fault_raise(uint8_t code, uint16_t detail)
{
    if (faults < 8u) {
        fault_code[faults] = code;
        fault_limb[faults] = detail;
    }
    faults++;
}

uint8_t psi_update(uint8_t limb, int16_t ax, int16_t az)
{
    (void)ax;
    (void)az;
    samples[limb]++;
    return 0;
}

uint8_t psi_level(uint8_t limb)
{
    (void)limb;
    return 0;
}

cfg_state_t seq_state_index(const uint8_t levels[CFG_N_LIMBS])
{
    (void)levels;
    return 0;
}

#if CFG_LEVEL_CALIBRATION
void level_apply(uint8_t limb, int16_t *ax, int16_t *az)
{
    (void)limb;
    (void)ax;
    (void)az;
}
#endif

/* Power on both IMUs and the firmware's IMU side, and run until both are read. */
static void boot(int polls)
{
    uint8_t i;
    now_us = 0;
    busy_polls = polls;
    nack_polls = polls;
    busy_left = -1;
    faults = 0;
    sim_mpu_power_on(7);
    sim_mpu_attach(0x68);
    sim_mpu_attach(0x69);
    imucheck_init();
    for (i = 0; i < CFG_N_LIMBS; i++) {
        imucheck_power_up(i);
    }
}

/* One period: the tick, then `idle` service calls, then time moves to the next tick. */
static void period(int idle)
{
    int k;
    imucheck_read();
    for (k = 0; k < idle; k++) {
        imucheck_service();
    }
    now_us += TICK_US;
}

static void run_until_reading(int idle)
{
    int n;
    for (n = 0; n < 2000 && !(samples[0] && samples[1]); n++) {
        period(idle);
    }
}

/* With room for both reads in a period, each IMU is read once every tick and the tick
 * takes every result. */
static void test_each_imu_is_read_and_taken_every_tick_when_the_bus_has_the_time(void)
{
    int idle, n;
    for (idle = 2 * (3 + 1); idle <= 20; idle++) {
        boot(3);
        memset(samples, 0, sizeof samples);
        run_until_reading(idle);
        CHECK_EQ(faults, 0);
        CHECK(samples[0] && samples[1]);
        period(idle);
        memset(samples, 0, sizeof samples);
        memset(begun, 0, sizeof begun);
        for (n = 0; n < 100; n++) {
            period(idle);
        }
        CHECK_EQ(begun[0], 100);
        CHECK_EQ(begun[1], 100);
        CHECK_EQ(samples[0], 100);
        CHECK_EQ(samples[1], 100);
        CHECK_EQ(faults, 0);
    }
}

/* Whatever the phase of the bus against the tick, and also when the bus has room for
 * fewer reads than limbs: every result the bus gave is taken by a tick (none
 * overwritten or dropped), and no limb starves. */
static void test_no_result_is_ever_dropped_whatever_the_phase(void)
{
    int idle, polls, n;
    for (polls = 0; polls <= 5; polls++) {
        for (idle = 1; idle <= 16; idle++) {
            boot(polls);
            memset(samples, 0, sizeof samples);
            run_until_reading(idle);
            CHECK(samples[0] && samples[1]);
            memset(samples, 0, sizeof samples);
            memset(begun, 0, sizeof begun);
            for (n = 0; n < 60; n++) {
                period(idle);
            }
            /* at most the one on the bus at the end, and one finished but not yet taken */
            CHECK(abs((int)begun[0] - (int)samples[0]) <= 1 && abs((int)begun[1] - (int)samples[1]) <= 1);
            CHECK(samples[0] >= 10u && samples[1] >= 10u);
            CHECK(samples[0] <= 61u && samples[1] <= 61u); /* never more than once a tick */
            CHECK_EQ(faults, 0);
        }
    }
}

/* An IMU that dies is a fault within a few ticks, wherever the tick falls in its reads
 * (a NACKed transaction is shorter than a read, so the phase moves when it dies). Before
 * the fix, a round still on the bus at the tick restarted the in-flight limb and its
 * result was dropped; in phase with the tick (e.g. limb 0, 3 polls a read, 1 a NACK, 4
 * idle calls a tick) the dead IMU never faulted. */
static void test_a_dead_imu_faults_whatever_the_phase_of_the_tick(void)
{
    int idle, polls, nack, n;
    uint8_t limb;
    for (limb = 0; limb < 2; limb++) {
        for (polls = 0; polls <= 8; polls++) {
            for (nack = 0; nack <= polls; nack++) {
                for (idle = 1; idle <= 16; idle++) {
                    boot(polls);
                    memset(samples, 0, sizeof samples);
                    run_until_reading(idle);
                    CHECK(samples[0] && samples[1]);
                    nack_polls = nack;
                    sim_mpu_set_fault((uint8_t)(0x68 + limb), SIM_MPU_NO_ACK);
                    /* two failed reads in a row; a slow bus reads each IMU only every few ticks */
                    for (n = 0; n < 2 + 4 * (polls + 1 + idle) / (idle + 1) && faults == 0; n++) {
                        period(idle);
                    }
                    if (faults != 1u) {
                        printf("limb %u, %d polls a read, %d a NACK, %d idle calls a tick: %u faults after %d ticks\n",
                               limb, polls, nack, idle, faults, n);
                    }
                    CHECK_EQ(faults, 1);
                    CHECK_EQ(fault_code[0], PROTO_FAULT_IMU_NO_ACK);
                    CHECK_EQ(fault_limb[0], limb);
                    CHECK_EQ(imucheck_bad(), 1u << limb);
                }
            }
        }
    }
}

/* An IMU that answers only after the start-up deadline faults IMU_NO_ACK, and only then. */
static void test_an_imu_that_never_answers_faults_at_the_start_up_deadline(void)
{
    int n;
    boot(3);
    sim_mpu_set_fault(0x69, SIM_MPU_NO_ACK);
    for (n = 0; n < 400 && faults == 0; n++) {
        period(12);
    }
    CHECK_EQ(faults, 1);
    CHECK_EQ(fault_code[0], PROTO_FAULT_IMU_NO_ACK);
    CHECK_EQ(fault_limb[0], 1);
    /* MPU6050_STARTUP_TYP_US + MPU6050_STARTUP_MAX_US + 50 ms margin (imucheck.c) */
    CHECK(n >= 169 && n <= 172);
}

int main(void)
{
    RUN(test_each_imu_is_read_and_taken_every_tick_when_the_bus_has_the_time);
    RUN(test_no_result_is_ever_dropped_whatever_the_phase);
    RUN(test_a_dead_imu_faults_whatever_the_phase_of_the_tick);
    RUN(test_an_imu_that_never_answers_faults_at_the_start_up_deadline);
    return UNIT_EXIT();
}
