/* test_imubus.c - imubus.c's multiplexer select and second bus run in the background.
 *
 * A scripted HAL: every transaction stays HAL_I2C_BUSY for BUSY_POLLS polls, then
 * completes with the result the test set for its (bus, address). Limb 0 sits directly on
 * bus 0 at 0x68, limbs 1 and 2 behind the multiplexer 0x70 of bus 1 (channels 2 and 5),
 * both at 0x68 (robot_config.h written by tests/test_imubus_c.py). */
#include <string.h>

#include "hal.h"
#include "imubus.h"
#include "unit.h"

#define BUSY_POLLS 3
#define MAX_LOG 16

static struct {
    int busy;         /* polls left for the transaction in flight; <0: none */
    int8_t result;    /* what it will give */
    int8_t nack[2][128];
    uint8_t n;        /* transactions begun */
    uint8_t bus[MAX_LOG], addr[MAX_LOG], byte0[MAX_LOG];
} hal;

static void hal_reset(void)
{
    memset(&hal, 0, sizeof hal);
    hal.busy = -1;
}

uint32_t hal_micros(void)
{
    return 0;
}

int8_t hal_i2c_begin_bus(uint8_t bus, uint8_t addr7, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx)
{
    (void)rx;
    (void)nrx;
    if (hal.busy > 0 || bus > 1u) {
        return -1;
    }
    if (hal.n < MAX_LOG) {
        hal.bus[hal.n] = bus;
        hal.addr[hal.n] = addr7;
        hal.byte0[hal.n] = ntx ? tx[0] : 0;
    }
    hal.n++;
    hal.busy = BUSY_POLLS;
    hal.result = hal.nack[bus][addr7 & 0x7F] ? -1 : 0;
    return 0;
}

int8_t hal_i2c_begin(uint8_t addr7, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx)
{
    return hal_i2c_begin_bus(0, addr7, tx, ntx, rx, nrx);
}

int8_t hal_i2c_poll(void)
{
    if (hal.busy > 0) {
        hal.busy--;
        return HAL_I2C_BUSY;
    }
    return hal.result;
}

/* Poll until the transaction ends; the number of polls it took. */
static int finish(int8_t *r)
{
    int polls = 0;
    while ((*r = imubus_poll()) == HAL_I2C_BUSY) {
        polls++;
        if (polls > 100) {
            break;
        }
    }
    return polls;
}

static void test_a_direct_imu_is_one_transaction_on_its_bus(void)
{
    uint8_t reg = 0x3B, rx[6];
    int8_t r;
    hal_reset();
    imubus_init();
    CHECK_EQ(imubus_begin(0, 0x68, &reg, 1, rx, 6), 0);
    CHECK_EQ(hal.n, 1);
    CHECK_EQ(finish(&r), BUSY_POLLS);
    CHECK_EQ(r, 0);
    CHECK_EQ(hal.bus[0], 0);
    CHECK_EQ(imubus_switches(), 0);
}

static void test_the_select_is_a_background_transaction_then_the_imu_follows(void)
{
    uint8_t reg = 0x3B, rx[6];
    int8_t r;
    hal_reset();
    imubus_init();
    CHECK_EQ(imubus_begin(1, 0x68, &reg, 1, rx, 6), 0);
    CHECK_EQ(hal.n, 1); /* only the select has begun; begin returned at once */
    CHECK_EQ(hal.bus[0], 1);
    CHECK_EQ(hal.addr[0], 0x70);
    CHECK_EQ(hal.byte0[0], 1 << 2);
    CHECK_EQ(imubus_begin(2, 0x68, &reg, 1, rx, 6), -1); /* one at a time */
    CHECK_EQ(finish(&r), 2 * BUSY_POLLS);
    CHECK_EQ(r, 0);
    CHECK_EQ(hal.n, 2);
    CHECK_EQ(hal.bus[1], 1);
    CHECK_EQ(hal.addr[1], 0x68);
    CHECK_EQ(hal.byte0[1], 0x3B);
    /* the same channel again: no select */
    CHECK_EQ(imubus_begin(1, 0x68, &reg, 1, rx, 6), 0);
    CHECK_EQ(hal.n, 3);
    CHECK_EQ(hal.addr[2], 0x68);
    (void)finish(&r);
    /* the other channel: a select first */
    CHECK_EQ(imubus_begin(2, 0x68, &reg, 1, rx, 6), 0);
    CHECK_EQ(hal.addr[3], 0x70);
    CHECK_EQ(hal.byte0[3], 1 << 5);
    (void)finish(&r);
    CHECK_EQ(r, 0);
    CHECK_EQ(imubus_switches(), 2);
}

static void test_a_failed_select_never_reads_through_the_wrong_channel(void)
{
    uint8_t reg = 0x3B, rx[6];
    int8_t r;
    hal_reset();
    imubus_init();
    CHECK_EQ(imubus_begin(1, 0x68, &reg, 1, rx, 6), 0);
    (void)finish(&r);
    hal.nack[1][0x70] = 1;
    CHECK_EQ(imubus_begin(2, 0x68, &reg, 1, rx, 6), 0);
    (void)finish(&r);
    CHECK(r < 0);
    CHECK_EQ(hal.n, 3); /* select 2, read, failed select: the IMU was not addressed */
    hal.nack[1][0x70] = 0;
    /* the channel is not known any more: limb 1's next read selects again */
    CHECK_EQ(imubus_begin(1, 0x68, &reg, 1, rx, 6), 0);
    CHECK_EQ(hal.addr[3], 0x70);
    (void)finish(&r);
    CHECK_EQ(r, 0);
}

int main(void)
{
    RUN(test_a_direct_imu_is_one_transaction_on_its_bus);
    RUN(test_the_select_is_a_background_transaction_then_the_imu_follows);
    RUN(test_a_failed_select_never_reads_through_the_wrong_channel);
    return UNIT_EXIT();
}
