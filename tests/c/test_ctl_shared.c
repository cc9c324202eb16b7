/* Host unit tests of an actuator that drives several limbs (the paper's R1 with one
 * coil): both limbs on actuator 0. */
#include "ctl_unit.h"
#include "unit.h"

static void test_shared_actuator_heats_if_any_of_its_limbs_must_go_up(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    uint8_t target[CFG_N_LIMBS];
    psi_init();
    CHECK_EQ(CFG_N_ACTUATORS, 1);
    CHECK_EQ(ctl_limb_actuator(0), 0);
    CHECK_EQ(ctl_limb_actuator(1), 0);
    put(0, 30.0); /* level 1, must go down */
    put(1, 0.0);  /* level 0, must go up */
    target[0] = 0;
    target[1] = 1;
    ctl_demand(target, 5000, 2000, duty);
    CHECK_EQ(duty[0], 5000);
    target[1] = 0; /* both down */
    ctl_demand(target, 5000, 2000, duty);
    CHECK_EQ(duty[0], 0);
}

static void test_shared_actuator_lets_an_unsettled_limb_settle_before_holding_the_other(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    uint8_t target[CFG_N_LIMBS] = {1, 0};
    psi_init();
    psi_set_debounce(1);
    limbmap_init();
    ctl_reset();
    put(0, 40.0);
    put(1, 30.0);
    put(1, 18.5); /* level 0, but not yet below the settle edge under the band */
    CHECK_EQ(psi_level(1), 0);
    ctl_demand(target, 5000, 2000, duty);
    CHECK_EQ(duty[0], 0); /* release wins over the other limb's hold */
    put(1, 10.0);         /* settled */
    ctl_demand(target, 5000, 2000, duty);
    CHECK_EQ(duty[0], 0); /* limb 0 above its hold top: off */
    put(0, 20.0);         /* limb 0 sags: the shared coil heats */
    ctl_demand(target, 5000, 2000, duty);
    CHECK_EQ(duty[0], 5000);
}

int main(void)
{
    RUN(test_shared_actuator_heats_if_any_of_its_limbs_must_go_up);
    RUN(test_shared_actuator_lets_an_unsettled_limb_settle_before_holding_the_other);
    return UNIT_EXIT();
}
