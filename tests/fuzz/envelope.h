/* envelope.h - the safety envelope's rules as an independent monitor for the fuzzers.
 *
 * Fed the PWM of every actuator channel after each control tick (host-sim virtual time),
 * it aborts the process on the first violation: a duty above max_duty; an on-period (duty
 * above the hold ceiling) longer than max_on + one tick; more than max_on + one tick of
 * on-time not yet paid back by cool-down (each µs not on pays max_on / min_cooldown µs);
 * a mean duty over any CFG_DUTY_WINDOW_MS window above CFG_MEAN_DUTY_PM (plus one tick);
 * any output while the E-stop is latched. Same rules as tests/test_safety_attacker.py.
 */
#ifndef PROLEG_FUZZ_ENVELOPE_H
#define PROLEG_FUZZ_ENVELOPE_H

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "robot_config.h"
#include "sma.h"

#define ENV_WINDOW_TICKS (CFG_DUTY_WINDOW_MS * 1000UL / CFG_TICK_US)

typedef struct {
    uint64_t on_us, debt_us, sum;
    uint16_t ring[ENV_WINDOW_TICKS];
    uint32_t pos;
} env_channel_t;

static env_channel_t env_ch[CFG_N_ACTUATORS];
static const uint8_t env_pins[CFG_N_ACTUATORS] = CFG_ACTUATOR_CHANNELS;

static void env_reset(void)
{
    memset(env_ch, 0, sizeof env_ch);
}

#define ENV_FAIL(...)                                      \
    do {                                                   \
        fprintf(stderr, "envelope violated: " __VA_ARGS__); \
        fputc('\n', stderr);                               \
        abort();                                           \
    } while (0)

static void env_after_tick(uint64_t now_us, uint16_t (*pwm)(uint8_t), uint8_t estopped)
{
    uint8_t i;
    for (i = 0; i < CFG_N_ACTUATORS; i++) {
        env_channel_t *c = &env_ch[i];
        uint16_t d = pwm(env_pins[i]);
        if (d > CFG_MAX_DUTY_PM) {
            ENV_FAIL("t=%llu channel %u duty %u > max", (unsigned long long)now_us, i, d);
        }
        if (estopped && d != 0u) {
            ENV_FAIL("t=%llu channel %u on while E-stopped", (unsigned long long)now_us, i);
        }
        if (d > CFG_HOLD_MAX_DUTY_PM) {
            c->on_us += CFG_TICK_US;
            c->debt_us += CFG_TICK_US;
            if (c->on_us > CFG_MAX_ON_MS * 1000ULL + CFG_TICK_US) {
                ENV_FAIL("t=%llu channel %u on for %llu us", (unsigned long long)now_us, i,
                         (unsigned long long)c->on_us);
            }
            if (c->debt_us > CFG_MAX_ON_MS * 1000ULL + CFG_TICK_US) {
                ENV_FAIL("t=%llu channel %u heats without its cool-down", (unsigned long long)now_us, i);
            }
        } else {
            uint64_t pay = CFG_MIN_COOLDOWN_MS ? (uint64_t)CFG_TICK_US * CFG_MAX_ON_MS / CFG_MIN_COOLDOWN_MS
                                               : c->debt_us;
            c->on_us = 0;
            c->debt_us = c->debt_us > pay ? c->debt_us - pay : 0u;
        }
        c->sum += d;
        c->sum -= c->ring[c->pos];
        c->ring[c->pos] = d;
        c->pos = (c->pos + 1u) % ENV_WINDOW_TICKS;
        if (c->sum > (uint64_t)CFG_MEAN_DUTY_PM * ENV_WINDOW_TICKS + CFG_MAX_DUTY_PM) {
            ENV_FAIL("t=%llu channel %u mean duty over the window too high", (unsigned long long)now_us, i);
        }
    }
}

#endif
