/* Replays per-tick duty requests through core/sma.c and prints what it lets through, for the
 * differential test of the claim bench's envelope model (tests/test_envelope_vs_sma.py).
 * stdin: one line per tick, "d0 d1" (requested duty of actuators 0 and 1, ‱); stdout: one line
 * per tick, "o0 o1 hits" (the duties applied, the on-limit hit bits). Ticks are CFG_TICK_US
 * apart; time comes from fake_now_us only. */
#include <stdio.h>

#include "fake_hal.h"
#include "sma.h"

int main(void)
{
    unsigned d0, d1;
    fake_hal_reset();
    fake_now_us = 0;
    sma_init(0);
    while (scanf("%u %u", &d0, &d1) == 2) {
        uint8_t hits;
        sma_request(0, (uint16_t)d0);
        sma_request(1, (uint16_t)d1);
        fake_now_us += CFG_TICK_US;
        hits = sma_tick(0);
        printf("%u %u %u\n", (unsigned)sma_duty(0), (unsigned)sma_duty(1), (unsigned)hits);
    }
    return 0;
}
