/* fuzz_app.c - libFuzzer harness of the whole firmware on the host-sim HAL (app_tick, the
 * command handler, the sequencer, the thermal budget) with the envelope checked after
 * every tick (envelope.h aborts on a violation).
 *
 * Input: a program of ops, each one byte, some followed by arguments:
 *   0x00-0x3E  write the next (op + 1) bytes to the UART as they are (noise, partial frames)
 *   0x3F       the board resets without losing power (sim_restart: cause (next byte & 3) + 2,
 *              external, brown-out, watchdog or software); the monitor goes on across it
 *   0x40-0x7F  run (op & 0x3F) + 1 ticks
 *   0x80-0xBF  run ((op & 0x3F) + 1) × 64 ticks (long waits: on-limits, timeouts, windows)
 *   0xC0-0xFF  limb = op & 1, what = (op >> 1) & 3:
 *              0: set the limb's true psi to (next byte - 128) / 2 degrees
 *              1: set the limb's IMU fault mode to (next byte & 3) (ok/no-ack/stuck/garbage)
 *              2: write a valid frame: next byte n % 48, then n bytes of id + payload
 *                 (CRC and COBS added here, so the command handler is reached)
 *              3: replay the last frame written with what = 2
 * At most 20,000 ticks (20 s of the fuzz build) per input.
 */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "cobs.h"
#include "crc16.h"
#include "envelope.h"

void sim_reset(uint32_t seed);
void sim_restart(uint8_t cause);
void sim_run_ticks(uint32_t n);
uint64_t sim_time_us(void);
uint16_t sim_pwm_duty(uint8_t ch);
void sim_uart_write(const uint8_t *data, uint32_t n);
uint32_t sim_uart_read(uint8_t *out, uint32_t cap);
void sim_imu_set_truth(uint8_t addr, double psi_deg, double dpsi_dps);
void sim_imu_set_fault(uint8_t addr, uint8_t mode);
uint8_t sim_limb_imu_addr(uint8_t limb);
uint8_t sim_n_limbs(void);

#define MAX_TICKS 20000UL

static uint32_t ticks_left;
static uint8_t last_frame[COBS_MAX_INPLACE + 2u];
static size_t last_len;

static void drain(void)
{
    static uint8_t out[4096];
    while (sim_uart_read(out, sizeof out) == sizeof out) {
    }
}

static void run(uint32_t n)
{
    while (n-- > 0u && ticks_left > 0u) {
        ticks_left--;
        sim_run_ticks(1);
        env_after_tick(sim_time_us(), sim_pwm_duty, sma_estopped());
    }
    drain();
}

static void write_frame(const uint8_t *body, size_t n)
{
    uint8_t buf[COBS_MAX_INPLACE + 2u];
    uint16_t crc;
    size_t enc;
    memcpy(buf + 1, body, n);
    crc = crc16_ccitt(CRC16_INIT, buf + 1, n);
    buf[1 + n] = (uint8_t)(crc & 0xFFu);
    buf[2 + n] = (uint8_t)(crc >> 8);
    enc = cobs_encode_inplace(buf, n + 2u);
    buf[enc] = 0;
    memcpy(last_frame, buf, enc + 1u);
    last_len = enc + 1u;
    sim_uart_write(buf, (uint32_t)(enc + 1u));
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    size_t i = 0;
    uint8_t limbs;
    sim_reset(1);
    env_reset();
    ticks_left = MAX_TICKS;
    last_len = 0;
    limbs = sim_n_limbs();
    while (i < size) {
        uint8_t op = data[i++];
        if (op == 0x3Fu) {
            if (i >= size) {
                break;
            }
            sim_restart((uint8_t)((data[i++] & 3u) + 2u));
            drain();
        } else if (op < 0x40u) {
            size_t n = (size_t)op + 1u;
            if (n > size - i) {
                n = size - i;
            }
            sim_uart_write(data + i, (uint32_t)n);
            i += n;
        } else if (op < 0x80u) {
            run((uint32_t)(op & 0x3Fu) + 1u);
        } else if (op < 0xC0u) {
            run(((uint32_t)(op & 0x3Fu) + 1u) * 64u);
        } else {
            uint8_t limb = (uint8_t)((op & 1u) % limbs);
            uint8_t what = (uint8_t)((op >> 1) & 3u);
            uint8_t addr = sim_limb_imu_addr(limb);
            if (what == 3u) {
                if (last_len) {
                    sim_uart_write(last_frame, (uint32_t)last_len);
                }
                continue;
            }
            if (i >= size) {
                break;
            }
            if (what == 0u) {
                sim_imu_set_truth(addr, ((int)data[i++] - 128) / 2.0, 0.0);
            } else if (what == 1u) {
                sim_imu_set_fault(addr, (uint8_t)(data[i++] & 3u));
            } else {
                size_t n = data[i++] % 48u;
                if (n > size - i) {
                    n = size - i;
                }
                write_frame(data + i, n);
                i += n;
            }
        }
    }
    run(1);
    return 0;
}
