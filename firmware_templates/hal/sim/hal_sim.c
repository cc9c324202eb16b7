/* hal_sim.c - the simulated board: hal.h on the host, plus the host-sim ABI that
 * proleg.sim.board drives through ctypes (docs/ARCHITECTURE.md).
 *
 * Virtual time: sim_run_ticks(n) advances the clock by CFG_TICK_US and runs app_tick()
 * once per tick; nothing depends on wall-clock time, so a seed gives the same run.
 * UART: host → board bytes go straight into the core's receive ring (uart.h, as a real
 * board's receive interrupt would put them); the core's transmit ring drains to the host
 * FIFO at the board's baud rate (10 bits per byte), so telemetry overruns show up as
 * they would on hardware. The ring sizes are the board file's [uart] buffers. PWM: the
 * duty the firmware set, per board channel. I2C: the register-level MPU-6050 models of
 * sim_mpu6050.c at the robot's IMU addresses. main() is not in this image (the board
 * file's build.main_loop = false): sim_reset/sim_run_ticks drive app_init/app_tick.
 */
#include <string.h>

#include "app.h"
#include "hal.h"
#include "robot_config.h"
#include "sim_mpu6050.h"
#include "uart.h"

#define SIM_API __attribute__((visibility("default")))

#define HOSTQ_SIZE 65536u /* wire → host, until sim_uart_read */

typedef struct {
    uint8_t *buf;
    uint32_t cap, head, count;
} fifo_t;

static uint8_t hostq_mem[HOSTQ_SIZE];
static fifo_t hostq = {hostq_mem, HOSTQ_SIZE, 0, 0};

static const uint8_t limb_imu[CFG_N_LIMBS] = CFG_LIMB_IMU_ADDR;
static uint64_t now_us;
static uint64_t line_budget; /* bytes × 1e6 the line may still carry */
static uint16_t pwm[CFG_PWM_CHANNELS];
static uint32_t uart_dropped, i2c_count;

static uint32_t fifo_put(fifo_t *f, const uint8_t *data, uint32_t n)
{
    uint32_t i;
    for (i = 0; i < n && f->count < f->cap; i++) {
        f->buf[(f->head + f->count) % f->cap] = data[i];
        f->count++;
    }
    return i;
}

static int fifo_get(fifo_t *f)
{
    uint8_t b;
    if (f->count == 0u) {
        return -1;
    }
    b = f->buf[f->head];
    f->head = (f->head + 1u) % f->cap;
    f->count--;
    return b;
}

/* ------------------------------------------------------------------ hal.h */

void hal_init(void)
{
    memset(pwm, 0, sizeof pwm);
}

uint32_t hal_micros(void)
{
    return (uint32_t)now_us;
}

static int8_t i2c_result;

/* The transaction happens at once (virtual time does not pass inside a tick). */
int8_t hal_i2c_begin(uint8_t addr7, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx)
{
    i2c_count++;
    i2c_result = sim_mpu_transfer(addr7, tx, ntx, rx, nrx, now_us) == 0 ? 0 : -1;
    return 0;
}

int8_t hal_i2c_poll(void)
{
    return i2c_result;
}

void hal_pwm_set(uint8_t channel, uint16_t duty_permyriad)
{
    if (channel < CFG_PWM_CHANNELS) {
        pwm[channel] = duty_permyriad > 10000u ? 10000u : duty_permyriad;
    }
}

void hal_uart_tx_start(void)
{
    /* nothing to switch on: drain_line() empties the transmit ring at the line rate */
}

uint8_t hal_reset_cause(void)
{
    return HAL_RESET_POWER_ON; /* sim_reset is a power-on */
}

void hal_watchdog_feed(void)
{
    /* no watchdog: the host drives every tick (the emulated boards have one) */
}

void hal_tick_mark(uint8_t busy)
{
    (void)busy;
}

/* ------------------------------------------------------------------ host-sim ABI */

static void drain_line(void)
{
    line_budget += (uint64_t)CFG_UART_BAUD / 10u * CFG_TICK_US;
    while (line_budget >= 1000000u) {
        int c = uart_isr_tx();
        uint8_t b;
        if (c < 0) {
            break;
        }
        b = (uint8_t)c;
        if (fifo_put(&hostq, &b, 1) != 1u) {
            uart_dropped++;
        }
        line_budget -= 1000000u;
    }
    if (line_budget > 1000000u) {
        line_budget = 1000000u; /* an idle line stores no credit (the ring is empty here) */
    }
}

SIM_API void sim_reset(uint32_t seed)
{
    uint8_t i;
    now_us = 0;
    line_budget = 0;
    uart_dropped = 0;
    i2c_count = 0;
    hostq.head = hostq.count = 0;
    sim_mpu_power_on(seed);
    for (i = 0; i < CFG_N_LIMBS; i++) {
        sim_mpu_attach(limb_imu[i]);
    }
    hal_init();
    app_init();
}

SIM_API void sim_run_ticks(uint32_t n)
{
    uint32_t i;
    for (i = 0; i < n; i++) {
        now_us += CFG_TICK_US;
        app_idle(CFG_TICK_US); /* the wait before the tick: background work (IMU reads, telemetry) */
        app_tick();
        drain_line();
    }
}

SIM_API uint64_t sim_time_us(void)
{
    return now_us;
}

SIM_API uint32_t sim_tick_period_us(void)
{
    return CFG_TICK_US;
}

SIM_API uint16_t sim_pwm_duty(uint8_t ch)
{
    return ch < CFG_PWM_CHANNELS ? pwm[ch] : 0u;
}

SIM_API void sim_uart_write(const uint8_t *data, uint32_t n)
{
    uint32_t i;
    for (i = 0; i < n; i++) {
        if (uart_isr_rx(data[i]) != 0) {
            uart_dropped++;
        }
    }
}

SIM_API uint32_t sim_uart_read(uint8_t *out, uint32_t cap)
{
    uint32_t n = 0;
    while (n < cap && hostq.count > 0u) {
        out[n++] = (uint8_t)fifo_get(&hostq);
    }
    return n;
}

SIM_API void sim_imu_set_truth(uint8_t addr, double psi_deg, double dpsi_dps)
{
    sim_mpu_set_truth(addr, psi_deg, dpsi_dps);
}

SIM_API void sim_imu_set_fault(uint8_t addr, uint8_t mode)
{
    sim_mpu_set_fault(addr, mode);
}

SIM_API void sim_imu_set_noise(uint8_t addr, double accel_ug_rthz, double gyro_dps_rthz, double accel_offset_mg)
{
    sim_mpu_set_noise(addr, accel_ug_rthz, gyro_dps_rthz, accel_offset_mg);
}

SIM_API uint8_t sim_imu_peek_reg(uint8_t addr, uint8_t reg)
{
    return sim_mpu_peek(addr, reg);
}

/* ---- beyond the documented ABI: what a simulator needs to wire a robot up ---- */

SIM_API uint8_t sim_n_limbs(void)
{
    return CFG_N_LIMBS;
}

/* IMU address of limb i (0 when there is no such limb). */
SIM_API uint8_t sim_limb_imu_addr(uint8_t limb)
{
    return limb < CFG_N_LIMBS ? limb_imu[limb] : 0u;
}

SIM_API uint8_t sim_n_pwm_channels(void)
{
    return CFG_PWM_CHANNELS;
}

/* Bytes lost: host → board FIFO full, or host FIFO full (host not reading). */
SIM_API uint32_t sim_uart_dropped(void)
{
    return uart_dropped;
}

SIM_API uint32_t sim_i2c_transactions(void)
{
    return i2c_count;
}
