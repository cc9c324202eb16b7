/* Host unit tests of core/sma.c, the SMA drive safety envelope. Config: max_duty 0.8
 * (8000 ‰o), max_on 50 ms = 50 ticks, min_cooldown 20 ms = 20 ticks, 1 kHz tick. */
#include "fake_hal.h"
#include "sma.h"
#include "unit.h"

static void setup(void)
{
    fake_hal_reset();
    sma_init();
}

static void test_init_turns_every_board_channel_off(void)
{
    uint8_t ch;
    setup();
    for (ch = 0; ch < CFG_PWM_CHANNELS; ch++) {
        CHECK_EQ(fake_pwm[ch], 0);
    }
}

static void test_every_output_is_clamped_to_the_duty_ceiling(void)
{
    setup();
    CHECK_EQ(CFG_MAX_DUTY_PM, 8000);
    sma_request(0, 10000);
    sma_request(1, 7999);
    sma_tick();
    CHECK_EQ(fake_pwm[0], 8000);
    CHECK_EQ(sma_duty(0), 8000);
    CHECK_EQ(fake_pwm[1], 7999);
    CHECK_EQ(sma_take_clamped(), 1);
    CHECK_EQ(sma_take_clamped(), 0);
    CHECK_EQ(sma_clamp(65535u), 8000);
}

static void test_actuators_drive_their_configured_channels(void)
{
    static const uint8_t channel[CFG_N_ACTUATORS] = CFG_ACTUATOR_CHANNELS;
    uint8_t a;
    setup();
    for (a = 0; a < CFG_N_ACTUATORS; a++) {
        sma_request(a, (uint16_t)(1000u + a));
    }
    sma_tick();
    for (a = 0; a < CFG_N_ACTUATORS; a++) {
        CHECK_EQ(fake_pwm[channel[a]], 1000u + a);
    }
}

static void test_max_on_time_forces_cooldown_then_allows_heating_again(void)
{
    uint32_t t;
    setup();
    sma_request(0, 6000);
    for (t = 1; t <= CFG_MAX_ON_TICKS; t++) {
        CHECK_EQ(sma_tick(), 0);
        CHECK_EQ(fake_pwm[0], 6000);
    }
    CHECK_EQ(sma_tick(), 1); /* one tick past max_on: forced off, reported */
    CHECK_EQ(fake_pwm[0], 0);
    CHECK(sma_cooling(0));
    CHECK_EQ(sma_limit_hits(), 1);
    for (t = 0; t < CFG_MIN_COOLDOWN_TICKS; t++) {
        sma_tick();
        CHECK_EQ(fake_pwm[0], 0);
    }
    CHECK(!sma_cooling(0));
    sma_tick();
    CHECK_EQ(fake_pwm[0], 6000);
}

static void test_short_bursts_do_not_accumulate_on_time(void)
{
    uint32_t t;
    int round;
    setup();
    for (round = 0; round < 10; round++) {
        sma_request(0, 5000);
        for (t = 0; t < CFG_MAX_ON_TICKS; t++) {
            CHECK_EQ(sma_tick(), 0);
        }
        sma_request(0, 0);
        CHECK_EQ(sma_tick(), 0);
    }
    CHECK_EQ(sma_limit_hits(), 0);
}

static void test_estop_turns_every_mosfet_off_within_one_tick(void)
{
    uint8_t ch;
    int t;
    setup();
    sma_request(0, 6000);
    sma_request(1, 6000);
    sma_tick();
    CHECK_EQ(fake_pwm[0], 6000);
    sma_estop(); /* no tick in between: off when the call returns */
    for (ch = 0; ch < CFG_PWM_CHANNELS; ch++) {
        CHECK_EQ(fake_pwm[ch], 0);
    }
    for (t = 0; t < 100; t++) { /* latched: requests are ignored */
        sma_request(0, 6000);
        sma_request(1, 6000);
        sma_tick();
        CHECK_EQ(fake_pwm[0], 0);
        CHECK_EQ(fake_pwm[1], 0);
    }
    CHECK(sma_estopped());
    sma_clear_estop();
    sma_request(0, 6000);
    sma_tick();
    CHECK_EQ(fake_pwm[0], 6000);
}

static void test_all_off_turns_every_board_channel_off_at_once(void)
{
    uint8_t ch;
    setup();
    sma_request(0, 6000);
    sma_request(1, 6000);
    sma_tick();
    for (ch = 0; ch < CFG_PWM_CHANNELS; ch++) {
        fake_pwm[ch] = 0x5555u; /* whatever a channel had */
    }
    sma_all_off();
    for (ch = 0; ch < CFG_PWM_CHANNELS; ch++) {
        CHECK_EQ(fake_pwm[ch], 0);
    }
    CHECK(!sma_estopped());
}

static void test_run_time_limits_may_narrow_but_never_widen_the_envelope(void)
{
    setup();
    CHECK(sma_set_limits(8001, CFG_MAX_ON_TICKS, CFG_MIN_COOLDOWN_TICKS) != 0);
    CHECK(sma_set_limits(8000, CFG_MAX_ON_TICKS + 1u, CFG_MIN_COOLDOWN_TICKS) != 0);
    CHECK(sma_set_limits(8000, CFG_MAX_ON_TICKS, CFG_MIN_COOLDOWN_TICKS - 1u) != 0);
    CHECK_EQ(sma_max_duty(), 8000);
    CHECK_EQ(sma_set_limits(5000, 10, CFG_MIN_COOLDOWN_TICKS + 5u), 0);
    CHECK_EQ(sma_max_duty(), 5000);
    sma_request(0, 6000);
    sma_tick();
    CHECK_EQ(fake_pwm[0], 5000);
}

int main(void)
{
    RUN(test_init_turns_every_board_channel_off);
    RUN(test_every_output_is_clamped_to_the_duty_ceiling);
    RUN(test_actuators_drive_their_configured_channels);
    RUN(test_max_on_time_forces_cooldown_then_allows_heating_again);
    RUN(test_short_bursts_do_not_accumulate_on_time);
    RUN(test_estop_turns_every_mosfet_off_within_one_tick);
    RUN(test_all_off_turns_every_board_channel_off_at_once);
    RUN(test_run_time_limits_may_narrow_but_never_widen_the_envelope);
    return UNIT_EXIT();
}
