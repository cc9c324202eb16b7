/* Host unit tests of core/ctl.c: measured level vs target → duty per actuator.
 * Config: two limbs, ψ* = 20°, band 19..21°, hold margin 1° (a held level is kept at
 * or above 22°, the settle edge below the band is 18°), limb i driven by actuator i. */
#include <math.h>

#include "ctl.h"
#include "psi.h"
#include "unit.h"

#define PI_D 3.14159265358979323846
#define DRIVE 6000u
#define HOLD 2500u

static void put(uint8_t limb, double deg)
{
    psi_update(limb, (int16_t)lround(8192.0 * sin(deg * PI_D / 180.0)),
               (int16_t)lround(8192.0 * cos(deg * PI_D / 180.0)));
}

static void demand(uint8_t t0, uint8_t t1, uint16_t duty[CFG_N_ACTUATORS])
{
    uint8_t target[CFG_N_LIMBS];
    target[0] = t0;
    target[1] = t1;
    ctl_demand(target, DRIVE, HOLD, duty);
}

static void setup(void)
{
    psi_init();
    psi_set_debounce(1);
}

static void test_limb_that_must_go_up_gets_the_drive_duty(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    setup();
    put(0, 0.0);
    put(1, 0.0);
    demand(1, 0, duty);
    CHECK_EQ(duty[0], DRIVE);
    CHECK_EQ(duty[1], 0);
}

static void test_limb_that_must_go_down_is_switched_off(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    setup();
    put(0, 30.0);
    put(1, 30.0);
    demand(0, 0, duty);
    CHECK_EQ(duty[0], 0);
    CHECK_EQ(duty[1], 0);
}

static void test_holding_a_raised_level_drives_below_the_hold_edge_and_keeps_warm_above(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    setup();
    CHECK_EQ(CFG_HOLD_MARGIN_CDEG, 100);
    put(0, 30.0);
    demand(1, 0, duty);
    CHECK_EQ(duty[0], HOLD); /* above the hold edge: keep the coil warm */
    put(0, 20.0);            /* inside the band: still level 1, sagging: drive */
    CHECK_EQ(psi_level(0), 1);
    demand(1, 0, duty);
    CHECK_EQ(duty[0], DRIVE);
    put(0, 21.5); /* above the band but inside the margin: still drive */
    demand(1, 0, duty);
    CHECK_EQ(duty[0], DRIVE);
    put(0, 22.3); /* above the hold edge: back to the hold duty */
    demand(1, 0, duty);
    CHECK_EQ(duty[0], HOLD);
}

static void test_a_hold_duty_of_zero_holds_by_feedback_alone(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    uint8_t target[CFG_N_LIMBS] = {1, 0};
    setup();
    put(0, 30.0);
    ctl_demand(target, DRIVE, 0, duty);
    CHECK_EQ(duty[0], 0);
    put(0, 20.0);
    ctl_demand(target, DRIVE, 0, duty);
    CHECK_EQ(duty[0], DRIVE);
}

static void test_limbs_rising_together_wait_for_the_farthest(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    setup();
    put(0, 15.0); /* 6° to go to the band's upper edge */
    put(1, 5.0);  /* 16° to go */
    demand(1, 1, duty);
    CHECK_EQ(duty[0], HOLD);
    CHECK_EQ(duty[1], DRIVE);
    put(1, 12.0); /* 9° to go: still more than the 2° window behind */
    demand(1, 1, duty);
    CHECK_EQ(duty[0], HOLD);
    put(1, 13.5); /* 7.5° to go: within the window, both heat */
    demand(1, 1, duty);
    CHECK_EQ(duty[0], DRIVE);
    CHECK_EQ(duty[1], DRIVE);
}

static void test_a_limb_rising_while_another_falls_waits_near_its_crossing(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    setup();
    put(0, 5.0);  /* rising, 16° to go */
    put(1, 30.0); /* level 1, falling, 11° above the band's lower edge */
    demand(1, 0, duty);
    CHECK_EQ(duty[0], DRIVE); /* far from its crossing: climbs */
    CHECK_EQ(duty[1], 0);     /* a falling limb is never held back */
    put(0, 16.0);             /* 5° to go: inside the 6° zone, waits */
    demand(1, 0, duty);
    CHECK_EQ(duty[0], HOLD);
    CHECK_EQ(duty[1], 0);
    put(1, 20.5); /* the falling limb is 1.5° from crossing: go */
    demand(1, 0, duty);
    CHECK_EQ(duty[0], DRIVE);
    CHECK_EQ(duty[1], 0);
}

static void test_a_falling_limb_waits_while_a_held_limb_sags(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    setup();
    put(0, 30.0);
    put(1, 30.0);
    demand(1, 0, duty); /* limb 0 holds, limb 1 falls */
    CHECK_EQ(duty[0], HOLD);
    CHECK_EQ(duty[1], 0);
    put(0, 20.5); /* limb 0 sags below its hold edge (still level 1) */
    CHECK_EQ(psi_level(0), 1);
    demand(1, 0, duty);
    CHECK_EQ(duty[0], DRIVE);
    CHECK_EQ(duty[1], HOLD); /* its coil kept warm: it stops relaxing */
    put(0, 23.0);            /* caught */
    demand(1, 0, duty);
    CHECK_EQ(duty[1], 0);
}

static void test_holding_level_zero_never_heats(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    setup();
    put(0, 5.0);
    put(1, 20.5);
    demand(0, 0, duty);
    CHECK_EQ(duty[0], 0);
    CHECK_EQ(duty[1], 0);
}

static void test_unknown_level_never_heats(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    setup();
    demand(1, 1, duty);
    CHECK_EQ(duty[0], 0);
    CHECK_EQ(duty[1], 0);
}

int main(void)
{
    RUN(test_limb_that_must_go_up_gets_the_drive_duty);
    RUN(test_limb_that_must_go_down_is_switched_off);
    RUN(test_holding_a_raised_level_drives_below_the_hold_edge_and_keeps_warm_above);
    RUN(test_a_hold_duty_of_zero_holds_by_feedback_alone);
    RUN(test_limbs_rising_together_wait_for_the_farthest);
    RUN(test_a_limb_rising_while_another_falls_waits_near_its_crossing);
    RUN(test_a_falling_limb_waits_while_a_held_limb_sags);
    RUN(test_holding_level_zero_never_heats);
    RUN(test_unknown_level_never_heats);
    return UNIT_EXIT();
}
