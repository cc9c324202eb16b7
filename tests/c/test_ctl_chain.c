/* Host unit tests of core/ctl.c on a chain of three limbs (robots/inchworm-3.toml: tail,
 * middle, head; ψ* = 20°, band 19..21°, limb i driven by actuator i): a falling limb waits
 * warm only for a sagging NEIGHBOUR (the coils that bend its body section), not for every
 * held limb of the robot, and only for one about to drop a level (within 2° of its band). */
#include "ctl_unit.h"
#include "unit.h"

static void demand3(uint8_t t0, uint8_t t1, uint8_t t2, uint16_t duty[CFG_N_ACTUATORS])
{
    uint8_t target[CFG_N_LIMBS];
    target[0] = t0;
    target[1] = t1;
    target[2] = t2;
    ctl_demand(target, DRIVE, HOLD, duty);
}

static void test_a_falling_limb_does_not_wait_for_a_sagging_limb_two_sections_away(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    setup();
    put(0, 30.0);
    put(1, 30.0);
    put(2, 30.0);
    demand3(1, 1, 0, duty); /* tail and middle held (above their tops: off), head falls */
    CHECK_EQ(duty[0], 0);
    CHECK_EQ(duty[1], 0);
    CHECK_EQ(duty[2], 0);
    put(0, 20.5); /* the tail sags below its hold edge (still level 1) */
    CHECK_EQ(psi_level(0), 1);
    demand3(1, 1, 0, duty);
    CHECK_EQ(duty[0], DRIVE); /* the tail re-heats its own coil */
    CHECK_EQ(duty[2], 0);     /* the head is not what holds the tail up: it goes on falling */
}

static void test_a_falling_limb_waits_warm_for_a_sagging_neighbour(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    setup();
    put(0, 30.0);
    put(1, 30.0);
    put(2, 30.0);
    demand3(1, 1, 0, duty);
    put(1, 20.5); /* the middle, next to the falling head, sags */
    CHECK_EQ(psi_level(1), 1);
    demand3(1, 1, 0, duty);
    CHECK_EQ(duty[1], DRIVE);
    CHECK_EQ(duty[2], HOLD); /* kept warm: it may be what holds the middle up */
    CHECK_EQ(duty[0], 0);
}

static void test_a_falling_first_limb_waits_for_its_only_neighbour(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    setup();
    put(0, 30.0);
    put(1, 30.0);
    put(2, 30.0);
    demand3(0, 1, 1, duty); /* the tail falls, middle and head held */
    put(2, 20.5);           /* the head (two sections away) sags: no wait */
    demand3(0, 1, 1, duty);
    CHECK_EQ(duty[2], DRIVE);
    CHECK_EQ(duty[0], 0);
    put(1, 20.5); /* now the middle sags too */
    demand3(0, 1, 1, duty);
    CHECK_EQ(duty[0], HOLD);
}

static void test_a_falling_limb_does_not_wait_for_a_neighbour_sagging_far_above_its_band(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    setup();
    put(0, 30.0);
    put(1, 30.0);
    put(2, 30.0);
    demand3(1, 1, 0, duty); /* tail and middle held, head falls */
    put(1, 23.0);           /* the middle, tilted by the falling head, is below its hold edge
                             * (25°) but 4° clear of its band (19..21°): it re-heats, and the
                             * head goes on falling */
    demand3(1, 1, 0, duty);
    CHECK_EQ(duty[1], DRIVE);
    CHECK_EQ(duty[2], 0);
    put(1, 20.9); /* now within 2° of dropping a level: the head waits warm */
    demand3(1, 1, 0, duty);
    CHECK_EQ(duty[1], DRIVE);
    CHECK_EQ(duty[2], HOLD);
}

#define HOVER_TICKS ((uint32_t)CTL_HOVER_MS * CFG_TICK_HZ / 1000u)

/* Limb `limb` at `deg` inside the band around ψ* = 20° (19..21°) for `ticks` control ticks
 * of targets (t0, t1, t2), the other limbs at 30° or 10° as their targets say; whether it
 * settled. */
static uint8_t in_the_band(uint8_t t0, uint8_t t1, uint8_t t2, uint8_t limb, double from, double deg, uint32_t ticks)
{
    uint16_t duty[CFG_N_ACTUATORS];
    uint8_t tg[3];
    uint32_t k;
    uint8_t i;
    tg[0] = t0;
    tg[1] = t1;
    tg[2] = t2;
    setup();
    for (i = 0; i < 3; i++) {
        put(i, i == limb ? from : (tg[i] ? 30.0 : 10.0));
    }
    demand3(t0, t1, t2, duty);
    for (k = 0; k < ticks; k++) {
        for (i = 0; i < 3; i++) {
            put(i, i == limb ? deg : (tg[i] ? 30.0 : 10.0));
        }
        demand3(t0, t1, t2, duty);
    }
    return psi_settled(limb);
}

static void test_a_limb_its_neighbours_hold_up_into_the_band_above_settles_a_while_after_relaxing(void)
{
    /* caterpillar-4's front proleg in 0101: its target level 0, its neighbours raised, the
     * body holds it at 20° (its level still 0 by hysteresis, coming from below): relaxed to the
     * band edges it still is not clear of the band; a hover time later it settles */
    CHECK(!in_the_band(1, 0, 1, 1, 10.0, 20.0, HOVER_TICKS + HOVER_TICKS / 2u));
    CHECK(in_the_band(1, 0, 1, 1, 10.0, 20.0, 2u * HOVER_TICKS + 20u));
    CHECK_EQ(psi_level(1), 0);
}

static void test_a_limb_that_sags_into_the_band_below_its_level_does_not_settle_there(void)
{
    /* held at level 1, sagging into the band from above: too low, not held up */
    CHECK(!in_the_band(1, 1, 1, 1, 30.0, 19.5, 4u * HOVER_TICKS));
    CHECK_EQ(psi_level(1), 1);
}

#define FALL_STALL_TICKS ((uint32_t)CTL_FALL_STALL_MS * CFG_TICK_HZ / 1000u)

/* `ticks` control ticks of targets (1, 1, 0): tail at 30°, middle at `middle`, the head at
 * `head` + `rate` degrees a tick. */
static void falling_head(double middle, double head, double rate, uint32_t ticks, uint16_t duty[CFG_N_ACTUATORS])
{
    uint32_t k;
    for (k = 0; k < ticks; k++) {
        put(0, 30.0);
        put(1, middle);
        put(2, head + rate * (double)k);
        demand3(1, 1, 0, duty);
    }
}

static void test_a_falling_limb_its_neighbours_hold_up_has_them_held_low(void)
{
    /* caterpillar-4's rear proleg in 1110 -> 1010: cold, stopped in the band above its target
     * level by its neighbours' holds. The inchworm's head stopped at 20.5° (band 19..21°). */
    uint16_t duty[CFG_N_ACTUATORS];
    setup();
    falling_head(30.0, 30.0, 0.0, 1u, duty);
    falling_head(30.0, 20.5, 0.0, FALL_STALL_TICKS / 2u, duty);
    CHECK_EQ(psi_level(2), 1);
    falling_head(23.0, 20.5, 0.0, 1u, duty); /* the middle 2° below its hold edge (25°) */
    CHECK_EQ(duty[1], DRIVE);                 /* not held up long enough: the usual hold */
    falling_head(23.0, 20.5, 0.0, FALL_STALL_TICKS, duty);
    CHECK_EQ(duty[1], 0); /* held low: clear of its band (upper edge 21°), off */
    CHECK_EQ(duty[0], 0);
    CHECK_EQ(duty[2], 0);
    falling_head(20.8, 20.5, 0.0, 1u, duty); /* into its band: heated back to its edge */
    CHECK_EQ(duty[1], DRIVE);
    CHECK_EQ(duty[2], 0); /* the head does not wait warm for it: that is what held it up */
    CHECK_EQ(psi_level(1), 1);
    falling_head(23.0, 18.0, 0.0, 20u, duty); /* the head got down: the usual hold again */
    CHECK_EQ(psi_level(2), 0);
    CHECK_EQ(duty[1], DRIVE);
}

static void test_a_falling_limb_stopped_far_above_its_band_does_not_lower_the_holds(void)
{
    /* its coil still cooling to Ms (a hot enclosure): 4° above its band for twice the watch */
    uint16_t duty[CFG_N_ACTUATORS];
    setup();
    falling_head(30.0, 30.0, 0.0, 1u, duty);
    falling_head(23.0, 25.0, 0.0, 2u * FALL_STALL_TICKS, duty);
    CHECK_EQ(psi_level(2), 1);
    CHECK_EQ(duty[1], DRIVE); /* the usual hold */
}

static void test_a_limb_that_falls_slowly_does_not_lower_the_holds(void)
{
    /* from 30° to 21.5° at 1°/s: a drop of 1° every second, under CTL_FALL_STALL_MS */
    uint16_t duty[CFG_N_ACTUATORS];
    uint32_t ticks = (uint32_t)(8.5 * CFG_TICK_HZ);
    setup();
    falling_head(30.0, 30.0, 0.0, 1u, duty);
    falling_head(23.0, 30.0, -1.0 / CFG_TICK_HZ, ticks, duty);
    CHECK_EQ(psi_level(2), 1);
    CHECK_EQ(duty[1], DRIVE);
}

int main(void)
{
    RUN(test_a_falling_limb_does_not_wait_for_a_sagging_limb_two_sections_away);
    RUN(test_a_falling_limb_waits_warm_for_a_sagging_neighbour);
    RUN(test_a_falling_first_limb_waits_for_its_only_neighbour);
    RUN(test_a_falling_limb_does_not_wait_for_a_neighbour_sagging_far_above_its_band);
    RUN(test_a_limb_its_neighbours_hold_up_into_the_band_above_settles_a_while_after_relaxing);
    RUN(test_a_limb_that_sags_into_the_band_below_its_level_does_not_settle_there);
    RUN(test_a_falling_limb_its_neighbours_hold_up_has_them_held_low);
    RUN(test_a_falling_limb_stopped_far_above_its_band_does_not_lower_the_holds);
    RUN(test_a_limb_that_falls_slowly_does_not_lower_the_holds);
    return UNIT_EXIT();
}
