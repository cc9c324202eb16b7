/* Host unit tests of core/ctl.c: measured level vs target → duty per actuator.
 * Config: two limbs, ψ* = 20°, band 19..21°, hold margin 1° (a held level is kept at
 * or above 22°), limb i driven by actuator i. */
#include <math.h>

#include "ctl.h"
#include "psi.h"
#include "unit.h"

#define PI_D 3.14159265358979323846
#define DRIVE 6000u

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
    ctl_demand(target, DRIVE, duty);
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

static void test_holding_a_raised_level_heats_only_below_the_hold_edge(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    setup();
    CHECK_EQ(CFG_HOLD_MARGIN_CDEG, 100);
    put(0, 30.0);
    demand(1, 0, duty);
    CHECK_EQ(duty[0], 0); /* above the hold edge: let it sag */
    put(0, 20.0);         /* inside the band: still level 1, heat a little */
    CHECK_EQ(psi_level(0), 1);
    demand(1, 0, duty);
    CHECK_EQ(duty[0], DRIVE);
    put(0, 21.5); /* above the band but inside the margin: still heat */
    demand(1, 0, duty);
    CHECK_EQ(duty[0], DRIVE);
    put(0, 22.3); /* above the hold edge: off again */
    demand(1, 0, duty);
    CHECK_EQ(duty[0], 0);
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
    RUN(test_holding_a_raised_level_heats_only_below_the_hold_edge);
    RUN(test_holding_level_zero_never_heats);
    RUN(test_unknown_level_never_heats);
    return UNIT_EXIT();
}
