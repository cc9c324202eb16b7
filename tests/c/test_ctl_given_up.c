/* Host unit tests of the fallback's hold rule (ctl.c GIVEN_UP): a limb whose own coil (the
 * build's map) the fallback gave up asks for no hold heat from the coil it is mapped to now;
 * it is still raised with it. Built against r1-fast (limb i on actuator i: the
 * CFG_LIMB_ACTUATOR_IS_INDEX shortcut) and r1-swapped (left on a1, right on a0:
 * limbmap_given_up, which no example robot compiles). */
#include "ctl_unit.h"
#include "unit.h"

static const uint8_t build_map[CFG_N_LIMBS] = CFG_LIMB_ACTUATOR;

/* The fallback's remap after losing limb `lost_limb`'s own coil: both limbs on the other one. */
static uint8_t give_up_coil_of(uint8_t lost_limb)
{
    static uint8_t both[CFG_N_LIMBS];
    uint8_t keep = build_map[1u - lost_limb];
    both[0] = keep;
    both[1] = keep;
    limbmap_use(build_map[lost_limb], both);
    return keep;
}

static void test_the_config_maps_as_named(void)
{
#ifdef TEST_SWAPPED
    CHECK_EQ(CFG_LIMB_ACTUATOR_IS_INDEX, 0);
    CHECK_EQ(build_map[0], 1);
    CHECK_EQ(build_map[1], 0);
#else
    CHECK_EQ(CFG_LIMB_ACTUATOR_IS_INDEX, 1);
#endif
    CHECK(CFG_FALLBACK);
}

static void test_a_given_up_limb_below_its_hold_edge_heats_no_coil(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    uint8_t lost;
    for (lost = 0; lost < 2u; lost++) {
        uint8_t other = (uint8_t)(1u - lost);
        uint8_t keep;
        setup();
        keep = give_up_coil_of(lost);
        CHECK(limbmap_given_up(lost));
        CHECK(!limbmap_given_up(other));
        put(lost, 30.0);
        put(other, 30.0);
        demand(1, 1, duty); /* both held above their hold tops: off */
        CHECK_EQ(duty[keep], 0);
        put(lost, 20.0); /* lifted by the body to 20°, below its hold edge (22°): still level 1 */
        CHECK_EQ(psi_level(lost), 1);
        demand(1, 1, duty);
        CHECK_EQ(duty[keep], 0); /* the remaining coil is not heated on for it */
        CHECK_EQ(duty[build_map[lost]], 0);
        put(other, 20.0); /* the remaining coil's own limb sags: its hold heats it */
        demand(1, 1, duty);
        CHECK_EQ(duty[keep], DRIVE);
    }
}

static void test_a_given_up_limb_is_still_raised_with_the_coil_it_is_mapped_to(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    uint8_t keep;
    setup();
    keep = give_up_coil_of(0);
    put(0, 5.0);
    put(1, 5.0);
    demand(1, 0, duty); /* limb 0 must rise: the fallback's coil raises it through the body */
    CHECK_EQ(duty[keep], DRIVE);
}

static void test_the_builds_map_taken_back_gives_up_nothing(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    uint16_t bad = 0;
    setup();
    (void)give_up_coil_of(0);
    CHECK_EQ(limbmap_set(build_map, 0, &bad), 0); /* n == 0: the build's map, the coil taken back */
    CHECK(!limbmap_given_up(0));
    put(0, 20.0);
    put(1, 30.0);
    demand(1, 1, duty);
    CHECK_EQ(duty[build_map[0]], DRIVE);
}

int main(void)
{
    RUN(test_the_config_maps_as_named);
    RUN(test_a_given_up_limb_below_its_hold_edge_heats_no_coil);
    RUN(test_a_given_up_limb_is_still_raised_with_the_coil_it_is_mapped_to);
    RUN(test_the_builds_map_taken_back_gives_up_nothing);
    return UNIT_EXIT();
}
