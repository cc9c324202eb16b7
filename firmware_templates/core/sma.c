/* sma.c - see sma.h. */
#include "sma.h"

#include "hal.h"
#include "rom.h"

static const uint8_t act_channel[CFG_N_ACTUATORS] ROM = CFG_ACTUATOR_CHANNELS;

typedef struct {
    uint32_t on_ticks;  /* consecutive ticks on */
    uint32_t cooldown;  /* ticks of forced off left */
    uint16_t request;   /* wanted duty */
    uint16_t applied;   /* last output */
} act_state_t;

static act_state_t acts[CFG_N_ACTUATORS];
static uint8_t estopped;
static uint16_t max_duty = CFG_MAX_DUTY_PM;
static uint32_t max_on = CFG_MAX_ON_TICKS;
static uint32_t cooldown = CFG_MIN_COOLDOWN_TICKS;
static uint16_t limit_hits;
static uint8_t clamped;
/* A variable, not the macro: comparing against a constant 0 would warn (-Wtype-limits). */
static const uint32_t min_cooldown = CFG_MIN_COOLDOWN_TICKS;

uint16_t sma_clamp(uint16_t duty_pm)
{
    uint16_t ceiling = max_duty < CFG_MAX_DUTY_PM ? max_duty : (uint16_t)CFG_MAX_DUTY_PM;
    return duty_pm > ceiling ? ceiling : duty_pm;
}

/* The only call of hal_pwm_set for actuators. */
static void output(uint8_t act, uint16_t duty_pm)
{
    uint16_t d = sma_clamp(duty_pm);
    if (d != duty_pm) {
        clamped = 1;
    }
    acts[act].applied = d;
    hal_pwm_set(ROM_U8(&act_channel[act]), d);
}

static void every_channel_off(void)
{
    uint8_t ch;
    uint8_t i;
    for (ch = 0; ch < CFG_PWM_CHANNELS; ch++) {
        hal_pwm_set(ch, 0);
    }
    for (i = 0; i < CFG_N_ACTUATORS; i++) {
        acts[i].request = 0;
        acts[i].applied = 0;
        acts[i].on_ticks = 0;
    }
}

void sma_init(void)
{
    uint8_t i;
    for (i = 0; i < CFG_N_ACTUATORS; i++) {
        acts[i].cooldown = 0;
    }
    estopped = 0;
    max_duty = CFG_MAX_DUTY_PM;
    max_on = CFG_MAX_ON_TICKS;
    cooldown = CFG_MIN_COOLDOWN_TICKS;
    limit_hits = 0;
    every_channel_off();
}

void sma_request(uint8_t act, uint16_t duty_pm)
{
    if (act < CFG_N_ACTUATORS) {
        acts[act].request = duty_pm;
    }
}

uint8_t sma_tick(void)
{
    uint8_t hit = 0;
    uint8_t i;
    for (i = 0; i < CFG_N_ACTUATORS; i++) {
        act_state_t *a = &acts[i];
        uint16_t duty = estopped ? 0u : a->request;
        if (a->cooldown > 0u) {
            a->cooldown--;
            duty = 0;
        }
        if (duty > 0u) {
            a->on_ticks++;
            if (a->on_ticks > max_on) {
                a->cooldown = cooldown;
                a->on_ticks = 0;
                duty = 0;
                hit = (uint8_t)(hit | (1u << i));
                if (limit_hits < 0xFFFFu) {
                    limit_hits++;
                }
            }
        } else {
            a->on_ticks = 0;
        }
        output(i, duty);
    }
    return hit;
}

void sma_all_off(void)
{
    every_channel_off();
}

void sma_estop(void)
{
    estopped = 1;
    every_channel_off();
}

void sma_clear_estop(void)
{
    estopped = 0;
}

uint8_t sma_estopped(void)
{
    return estopped;
}

int8_t sma_set_limits(uint16_t max_duty_pm, uint32_t max_on_ticks, uint32_t cooldown_ticks)
{
    if (max_duty_pm > CFG_MAX_DUTY_PM || max_on_ticks > CFG_MAX_ON_TICKS || cooldown_ticks < min_cooldown) {
        return -1;
    }
    max_duty = max_duty_pm;
    max_on = max_on_ticks;
    cooldown = cooldown_ticks;
    return 0;
}

uint16_t sma_max_duty(void)
{
    return sma_clamp(0xFFFFu);
}

uint16_t sma_duty(uint8_t act)
{
    return acts[act].applied;
}

uint8_t sma_cooling(uint8_t act)
{
    return acts[act].cooldown > 0u;
}

uint8_t sma_take_clamped(void)
{
    uint8_t c = clamped;
    clamped = 0;
    return c;
}

uint16_t sma_limit_hits(void)
{
    return limit_hits;
}
