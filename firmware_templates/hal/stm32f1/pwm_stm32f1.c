/* pwm_stm32f1.c - hal_pwm_set on the STM32F103: TIM2/TIM3/TIM4 channels from the board pin
 * map (CFG_PWM_MAP: {timer, channel, port 0=A 1=B, pin}), PWM mode 1 with preload, 1000
 * counts per period at CFG_PWM_HZ. Part of the stm32f1 HAL (hal_stm32f1.h).
 */
#include <stdint.h>

#include "hal.h"
#include "hal_stm32f1.h"
#include "robot_config.h"

#define PWM_COUNTS 1000u

typedef struct {
    uint8_t timer;   /* 2, 3 or 4 */
    uint8_t channel; /* 1..4 */
    uint8_t port;    /* 0 = GPIOA, 1 = GPIOB */
    uint8_t pin;
} pwm_pin_t;

static const pwm_pin_t pwm_map[CFG_PWM_CHANNELS] = CFG_PWM_MAP;

/* TIM2, TIM3, TIM4 sit 0x400 apart (RM0008 §3.3, Table 3); t is 2, 3 or 4 (family.toml). */
static uint32_t timer_base(uint8_t t)
{
    return TIM2_BASE + 0x400u * (uint32_t)(t - 2u);
}

void pwm_init(void)
{
    uint8_t i;
    uint32_t psc = sysclk / (PWM_COUNTS * CFG_PWM_HZ); /* timers on APB1 run at sysclk */
    RCC_APB1ENR |= RCC_APB1_TIM2 | RCC_APB1_TIM3 | RCC_APB1_TIM4;
    for (i = 0; i < CFG_PWM_CHANNELS; i++) {
        const pwm_pin_t *p = &pwm_map[i];
        uint32_t b = timer_base(p->timer);
        volatile uint32_t *ccmr = p->channel <= 2u ? &TIM_CCMR1(b) : &TIM_CCMR2(b);
        uint32_t shift = (p->channel & 1u) ? 0u : 8u;
        TIM_CCR(b, p->channel) = 0;
        *ccmr = (*ccmr & ~(0xFFu << shift)) | ((6u << 4 | 1u << 3) << shift); /* PWM mode 1, preload */
        TIM_CCER(b) |= 1u << (4u * (p->channel - 1u));
        TIM_PSC(b) = psc ? psc - 1u : 0u;
        TIM_ARR(b) = PWM_COUNTS - 1u;
        TIM_EGR(b) = 1u;
        TIM_CR1(b) = (1u << 7) | 1u; /* ARPE, CEN */
        gpio_mode(p->port, p->pin, GPIO_AF_PP_50MHZ);
    }
}

void hal_pwm_set(uint8_t channel, uint16_t duty)
{
    const pwm_pin_t *p;
    if (channel >= CFG_PWM_CHANNELS) {
        return;
    }
    p = &pwm_map[channel];
    if (duty > 10000u) {
        duty = 10000u;
    }
    /* CCR = ARR + 1 is 100 %, 0 is 0 %: no glitch at either end in PWM mode 1. */
    if (duty == 0u) {
        /* Off now, not at the end of the running PWM period: with the preload off for the
         * write, CCR takes the new value at once (RM0008 §15.3.9, OCxPE) and PWM mode 1 drops
         * the output as CNT >= 0; the counter, so every other channel, is not disturbed. */
        uint32_t b = timer_base(p->timer);
        volatile uint32_t *ccmr = p->channel <= 2u ? &TIM_CCMR1(b) : &TIM_CCMR2(b);
        uint32_t pe = (1u << 3) << ((p->channel & 1u) ? 0u : 8u);
        *ccmr &= ~pe;
        TIM_CCR(b, p->channel) = 0;
        *ccmr |= pe;
        return;
    }
    TIM_CCR(timer_base(p->timer), p->channel) = (uint32_t)duty * PWM_COUNTS / 10000u;
}
