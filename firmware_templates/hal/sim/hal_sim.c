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
 * sim_mpu6050.c (limb i's IMU is model slot i) on the buses, addresses and multiplexer
 * channels the robot's IMU placement names (CFG_LIMB_IMU_*), with the register-level
 * TCA9548A models of sim_tca9548a.c where a limb sits behind one. main() is not in this image (the board
 * file's build.main_loop = false): sim_reset/sim_run_ticks drive app_init/app_tick.
 */
#include <string.h>

#include "app.h"
#include "hal.h"
#include "robot_config.h"
#include "sim_mpu6050.h"
#include "sim_tca9548a.h"
#include "imubus.h"
#include "uart.h"

#define SIM_API __attribute__((visibility("default")))

#if CFG_LINK_CAN
void sim_can_drain(void); /* can_sim.c: the CAN bus at its bit rate */
#endif

#define HOSTQ_SIZE 65536u /* wire → host, until sim_uart_read */

typedef struct {
    uint8_t *buf;
    uint32_t cap, head, count;
} fifo_t;

static uint8_t hostq_mem[HOSTQ_SIZE];
static fifo_t hostq = {hostq_mem, HOSTQ_SIZE, 0, 0};

static const uint8_t limb_imu[CFG_N_LIMBS] = CFG_LIMB_IMU_ADDR;
static const uint8_t limb_bus[CFG_N_LIMBS] = CFG_LIMB_IMU_BUS;
static const uint8_t limb_mux[CFG_N_LIMBS] = CFG_LIMB_IMU_MUX;
static const uint8_t limb_channel[CFG_N_LIMBS] = CFG_LIMB_IMU_CHANNEL;
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

/* The I2C buses: a transfer reaches the multiplexer at that address, else every limb's
 * MPU-6050 model on that bus at that address that is wired directly or sits behind a
 * connected multiplexer channel (limb i's IMU is model slot i). Several devices that
 * answer at once drive the open-drain bus together: the host reads the AND of their bytes. */
static int bus_transfer(uint8_t bus, uint8_t addr7, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx)
{
    uint8_t tmp[255];
    uint8_t i, j, acked = 0;
    i2c_count++;
    if (sim_tca_transfer(bus, addr7, tx, ntx, rx, nrx) == 0) {
        return 0;
    }
    for (i = 0; i < CFG_N_LIMBS; i++) {
        if (limb_bus[i] != bus || limb_imu[i] != addr7 ||
            (limb_mux[i] != 0u && !sim_tca_enabled(bus, limb_mux[i], limb_channel[i]))) {
            continue;
        }
        if (sim_mpu_transfer_slot(i, tx, ntx, acked ? tmp : rx, nrx, now_us) != 0) {
            continue;
        }
        if (acked) {
            for (j = 0; j < nrx; j++) {
                rx[j] &= tmp[j];
            }
        }
        acked = 1;
    }
    return acked ? 0 : -1;
}

/* The model slot behind a host-sim ABI IMU key: 0x80 | limb, or the address of an IMU
 * wired directly to bus 0 (what sim_limb_imu_addr returns); -1 when there is none. */
static int imu_slot(uint8_t key)
{
    uint8_t i;
    if (key & 0x80u) {
        return (key & 0x7Fu) < CFG_N_LIMBS ? (int)(key & 0x7Fu) : -1;
    }
    for (i = 0; i < CFG_N_LIMBS; i++) {
        if (limb_bus[i] == 0u && limb_mux[i] == 0u && limb_imu[i] == key) {
            return i;
        }
    }
    return -1;
}

static int8_t i2c_result;

/* The transaction happens at once (virtual time does not pass inside a tick), through the
 * same bus model as the blocking call (multiplexers, several IMUs). */
int8_t hal_i2c_begin(uint8_t addr7, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx)
{
    i2c_result = bus_transfer(0, addr7, tx, ntx, rx, nrx) == 0 ? 0 : -1;
    return 0;
}

/* The same on bus `bus`: at once, through the same bus model. */
int8_t hal_i2c_begin_bus(uint8_t bus, uint8_t addr7, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx)
{
    i2c_result = bus_transfer(bus, addr7, tx, ntx, rx, nrx) == 0 ? 0 : -1;
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

/* sim_reset is a power-on; sim_restart(cause) a reset that is not */
static uint8_t reset_cause = HAL_RESET_POWER_ON;

uint8_t hal_reset_cause(void)
{
    return reset_cause;
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

/* The chip restarts: its clock from 0, the link's queues empty, the firmware from app_init. */
static void restart(void)
{
    now_us = 0;
    line_budget = 0;
    uart_dropped = 0;
    i2c_count = 0;
    hostq.head = hostq.count = 0;
    hal_init();
    app_init();
}

SIM_API void sim_reset(uint32_t seed)
{
    uint8_t i;
    reset_cause = HAL_RESET_POWER_ON;
    sim_mpu_power_on(seed);
    sim_tca_power_on();
    for (i = 0; i < CFG_N_LIMBS; i++) {
        sim_mpu_attach_slot(i);
        if (limb_mux[i] != 0u) {
            sim_tca_attach(limb_bus[i], limb_mux[i]);
        }
    }
    restart();
}

/* A reset that is not a power-on (HAL_RESET_EXTERNAL: a Nano's DTR auto-reset or the button;
 * HAL_RESET_BROWN_OUT, HAL_RESET_WATCHDOG, ...): the IMUs and multiplexers stay powered as they
 * were, and RAM keeps what a real chip's keeps (here every global; the firmware zeroes what it
 * does not keep). */
SIM_API void sim_restart(uint8_t cause)
{
    reset_cause = cause;
    restart();
}

SIM_API void sim_run_ticks(uint32_t n)
{
    uint32_t i;
    for (i = 0; i < n; i++) {
        now_us += CFG_TICK_US;
        app_idle(CFG_TICK_US); /* the wait before the tick: background work (IMU reads, telemetry) */
        app_tick();
        drain_line();
#if CFG_LINK_CAN
        sim_can_drain();
#endif
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
    sim_mpu_set_truth_slot((uint8_t)imu_slot(addr), psi_deg, dpsi_dps);
}

SIM_API void sim_imu_set_fault(uint8_t addr, uint8_t mode)
{
    sim_mpu_set_fault_slot((uint8_t)imu_slot(addr), mode);
}

SIM_API void sim_imu_set_noise(uint8_t addr, double accel_ug_rthz, double gyro_dps_rthz, double accel_offset_mg)
{
    sim_mpu_set_noise_slot((uint8_t)imu_slot(addr), accel_ug_rthz, gyro_dps_rthz, accel_offset_mg);
}

SIM_API uint8_t sim_imu_peek_reg(uint8_t addr, uint8_t reg)
{
    return sim_mpu_peek_slot((uint8_t)imu_slot(addr), reg);
}

/* ---- beyond the documented ABI: what a simulator needs to wire a robot up ---- */

SIM_API uint8_t sim_n_limbs(void)
{
    return CFG_N_LIMBS;
}

/* The key of limb i's IMU for sim_imu_* (0 when there is no such limb): its address
 * when it is wired directly to bus 0, else 0x80 | i (proleg.firmware.placement.sim_imu_keys). */
SIM_API uint8_t sim_limb_imu_addr(uint8_t limb)
{
    if (limb >= CFG_N_LIMBS) {
        return 0u;
    }
    return (limb_bus[limb] == 0u && limb_mux[limb] == 0u) ? limb_imu[limb] : (uint8_t)(0x80u | limb);
}

/* Multiplexer channel selects the firmware made (core/imubus.c) and the control
 * register of the multiplexer at (bus, addr). */
SIM_API uint32_t sim_mux_switches(void)
{
    return imubus_switches();
}

SIM_API uint8_t sim_mux_control(uint8_t bus, uint8_t addr)
{
    return sim_tca_control(bus, addr);
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

/* Non-volatile block (hal.h): memory that sim_reset keeps, as EEPROM survives a reset;
 * erased (0xFF) when the library is loaded. A write lands at the first poll after it
 * began (the next tick). */
static uint8_t nv[HAL_NV_BYTES];
static uint8_t nv_formatted;
static const uint8_t *nv_src;
static uint8_t nv_n;

static void nv_format(void)
{
    if (!nv_formatted) {
        memset(nv, 0xFF, sizeof nv);
        nv_formatted = 1;
    }
}

void hal_nv_read(uint8_t *dst, uint8_t n)
{
    nv_format();
    memcpy(dst, nv, n <= HAL_NV_BYTES ? n : HAL_NV_BYTES);
}

int8_t hal_nv_write(const uint8_t *src, uint8_t n)
{
    if (n > HAL_NV_BYTES || nv_src) {
        return -1;
    }
    nv_src = src;
    nv_n = n;
    return 0;
}

int8_t hal_nv_poll(void)
{
    if (!nv_src) {
        return 0;
    }
    nv_format();
    memcpy(nv, nv_src, nv_n);
    nv_src = 0;
    return 0;
}

/* The host's view of the block (inspect it, keep it in a file, corrupt it in a test). */
SIM_API uint8_t sim_nv_peek(uint8_t i)
{
    nv_format();
    return i < HAL_NV_BYTES ? nv[i] : 0xFFu;
}

SIM_API void sim_nv_poke(uint8_t i, uint8_t v)
{
    nv_format();
    if (i < HAL_NV_BYTES) {
        nv[i] = v;
    }
}
