/* Host unit tests of core/safety.c, the step guard (r1-fast: state timeout 200 ms, on-limit
 * latch after 3 hits). Time comes from fake_now_us only. */
#include "fake_hal.h"
#include "safety.h"
#include "unit.h"

#define TIMEOUT_US (CFG_STATE_TIMEOUT_MS * 1000UL)

static uint8_t act;

/* The coils sma.c heats in each tick (its sma_take_heated, which the guard asks every tick):
 * every one, unless a test says which. */
static uint8_t raised = 0xFFu;

uint8_t sma_take_heated(void)
{
    return raised;
}

static uint8_t tick_us(uint32_t us, uint8_t demanding, uint8_t reached, uint8_t hits)
{
    fake_now_us += us;
    return guard_tick(demanding, reached, hits, &act);
}

static uint8_t tick(uint8_t demanding, uint8_t reached, uint8_t hits)
{
    return tick_us(CFG_TICK_US, demanding, reached, hits);
}

static void setup(uint64_t t0)
{
    raised = 0xFFu;
    fake_hal_reset();
    fake_now_us = t0;
    guard_init();
}

/* Real µs of demand until the guard answers `want` (or 100 timeouts' worth). */
static uint32_t demand_until(uint8_t want, uint32_t period_us)
{
    uint32_t t = 0;
    while (t < 100u * TIMEOUT_US) {
        t += period_us;
        if (tick_us(period_us, 1, 0, 0) == want) {
            break;
        }
    }
    return t;
}

static void test_an_unreached_target_times_out_on_real_time(void)
{
    setup(0);
    CHECK_EQ(demand_until(GUARD_TIMEOUT, CFG_TICK_US), TIMEOUT_US);
}

static void test_the_timeout_is_right_across_the_clock_wrap_and_with_slow_ticks(void)
{
    uint32_t t;
    setup(0xFFFFFFFFull - 50000u);
    t = demand_until(GUARD_TIMEOUT, 3000u);
    CHECK(t >= TIMEOUT_US && t < TIMEOUT_US + 3000u);
}

static void test_time_not_demanding_does_not_count_but_a_restart_does_not_reset_it(void)
{
    uint32_t k;
    setup(0);
    for (k = 0; k < 150u; k++) {
        CHECK_EQ(tick(1, 0, 0), GUARD_OK);
    }
    for (k = 0; k < 5000u; k++) { /* STOP: nothing demanded for 5 s */
        CHECK_EQ(tick(0, 0, 0), GUARD_OK);
    }
    /* START again: 50 ms of the 200 ms are left */
    CHECK_EQ(demand_until(GUARD_TIMEOUT, CFG_TICK_US), TIMEOUT_US - 150u * CFG_TICK_US);
}

/* drive.c latches the timeout without testing again that a gait runs and no fault is
 * latched: the guard says GUARD_TIMEOUT only while `demanding`, even past its timeout. */
static void test_past_the_timeout_a_tick_not_demanding_is_ok(void)
{
    setup(0);
    CHECK_EQ(demand_until(GUARD_TIMEOUT, CFG_TICK_US), TIMEOUT_US);
    CHECK_EQ(tick(0, 0, 0), GUARD_OK);
    CHECK_EQ(tick(1, 0, 0), GUARD_TIMEOUT); /* the time still counts */
}

static void test_reaching_a_target_starts_the_next_step_afresh(void)
{
    uint32_t k;
    setup(0);
    for (k = 0; k < 190u; k++) {
        CHECK_EQ(tick(1, 0, 0), GUARD_OK);
    }
    CHECK_EQ(tick(0, 1, 0), GUARD_OK); /* reached: not demanding an unreached target */
    CHECK_EQ(demand_until(GUARD_TIMEOUT, CFG_TICK_US), TIMEOUT_US);
}

static void test_repeated_on_limit_hits_without_progress_latch(void)
{
    uint8_t k;
    setup(0);
    for (k = 1; k < CFG_ON_LIMIT_LATCH; k++) {
        CHECK_EQ(tick(0, 0, 0x02), GUARD_OK);
        CHECK_EQ(guard_hits(), k);
    }
    CHECK_EQ(tick(0, 0, 0x02), GUARD_ON_LIMIT);
    CHECK_EQ(act, 1);
    CHECK_EQ(tick(0, 0, 0), GUARD_ON_LIMIT); /* stays until acknowledged */
    guard_ack();
    CHECK_EQ(tick(0, 0, 0), GUARD_OK);
}

static void test_hits_on_different_steps_do_not_latch(void)
{
    uint8_t k;
    setup(0);
    for (k = 0; k < 10u; k++) {
        CHECK_EQ(tick(1, 0, 0x01), GUARD_OK);
        CHECK_EQ(tick(1, 1, 0), GUARD_OK); /* the step completed */
    }
}

/* A host restarting a gait past a dead coil re-reaches the states the other coils make:
 * that is no progress for the coil that keeps hitting its on-time limit. */
static void test_hits_latch_when_only_other_coils_lift_their_limbs_in_between(void)
{
    uint8_t k, j;
    setup(0);
    for (k = 1; k < CFG_ON_LIMIT_LATCH; k++) {
        raised = 0x02u; /* actuator 1 heats towards its target ... */
        for (j = 0; j < 20u; j++) {
            CHECK_EQ(tick(1, 0, 0), GUARD_OK);
        }
        raised = 0;
        CHECK_EQ(tick(1, 0, 0x02), GUARD_OK); /* ... and hits, cut */
        guard_started(); /* the host restarts the gait */
        raised = 0x01u;  /* and only actuator 0 heats on the way to the target reached */
        CHECK_EQ(tick(0, 1, 0), GUARD_OK); /* reached: not demanding an unreached target */
        CHECK_EQ(guard_hits(), k);
        CHECK_EQ(guard_unreached_us(), 0); /* the time still starts afresh at each reach */
    }
    CHECK_EQ(tick(1, 0, 0x02), GUARD_ON_LIMIT);
    CHECK_EQ(act, 1);
}

/* Hits while no coil has heated without progress (e.g. while a reached state is held):
 * the latch names the coil that hit. */
static void test_with_no_time_without_progress_the_latch_names_the_coil_that_hit(void)
{
    uint8_t k;
    setup(0);
    raised = 0;
    for (k = 1; k < CFG_ON_LIMIT_LATCH; k++) {
        CHECK_EQ(tick(0, 0, 0x02), GUARD_OK);
    }
    CHECK_EQ(tick(0, 0, 0x02), GUARD_ON_LIMIT);
    CHECK_EQ(act, 1);
}

static void test_hits_reset_once_every_coil_that_hit_has_heated_on_the_way_to_a_target(void)
{
    setup(0);
    raised = 0; /* a coil that hits is cut, not heated */
    CHECK_EQ(tick(1, 0, 0x03), GUARD_OK); /* both coils hit */
    CHECK_EQ(guard_hits(), 2);
    raised = 0x01u; /* actuator 0 heats, then its target is reached */
    CHECK_EQ(tick(1, 0, 0), GUARD_OK);
    raised = 0;
    CHECK_EQ(tick(1, 1, 0), GUARD_OK);
    CHECK_EQ(guard_hits(), 2); /* actuator 1 has not heated on the way to a target since */
    raised = 0x02u;
    CHECK_EQ(tick(1, 0, 0), GUARD_OK);
    raised = 0;
    CHECK_EQ(tick(1, 1, 0), GUARD_OK);
    CHECK_EQ(guard_hits(), 0);
}

/* What sma_tick decides in the tick of a reach heats after it (towards the next target, when
 * the step moved on at once: hold_ms 0): no progress to the target reached. Every START of R1's
 * gait with hold_ms 0 reached its rest state and heated the dead coil towards 10 in one tick, and
 * the coil's time and hits started again at every START (77 s of 120 s heated, no fault). */
static void test_heating_decided_in_the_tick_of_a_reach_is_no_progress_to_it(void)
{
    uint32_t k, run = 0;
    setup(0);
    raised = 0;
    CHECK_EQ(tick(1, 0, 0x02), GUARD_OK); /* the dead coil hit once */
    while (run < 10u) {
        raised = 0x02u; /* START: the state it stands in reached, the dead coil heats from this tick */
        guard_started();
        if (tick(1, 1, 0) != GUARD_OK) {
            break;
        }
        for (k = 0; k < 150u; k++) {
            if (tick(1, 0, 0) == GUARD_TIMEOUT) {
                break;
            }
        }
        if (k < 150u) {
            break;
        }
        raised = 0; /* STOP */
        CHECK_EQ(tick(0, 0, 0), GUARD_OK);
        run++;
    }
    CHECK_EQ(run, 1u); /* 150 ms a run, 200 ms the timeout: the second run */
    CHECK_EQ(guard_suspect(), 1);
    CHECK_EQ(guard_hits(), 1); /* its hit still counts */
}

static void test_the_operator_acknowledging_a_fault_restarts_the_step_time(void)
{
    setup(0);
    demand_until(GUARD_TIMEOUT, CFG_TICK_US);
    guard_ack();
    CHECK_EQ(guard_unreached_us(), 0);
    CHECK_EQ(demand_until(GUARD_TIMEOUT, CFG_TICK_US), TIMEOUT_US);
}

static void test_a_narrowed_timeout_applies_and_a_wider_one_counts_as_the_build_value(void)
{
    setup(0);
    guard_set_timeout_ms(50);
    CHECK_EQ(demand_until(GUARD_TIMEOUT, CFG_TICK_US), 50000u);
    setup(0);
    guard_set_timeout_ms(CFG_STATE_TIMEOUT_MS + 1u);
    CHECK_EQ(demand_until(GUARD_TIMEOUT, CFG_TICK_US), TIMEOUT_US);
}

/* A host restarting a gait past a dead coil: every START stands in a state the other coils
 * made, each reached at once, so the step's own time never passes the timeout; the dead
 * coil's time heated towards targets it never reached does, and names it. */
static void test_a_coil_that_heats_across_restarts_and_never_progresses_times_out(void)
{
    uint32_t k, run = 0;
    setup(0);
    while (run < 10u) {
        raised = 0x01u; /* the healthy coil lifts its limb: a target reached */
        CHECK_EQ(tick(1, 0, 0), GUARD_OK);
        CHECK_EQ(tick(1, 1, 0), GUARD_OK);
        raised = 0x02u; /* the dead coil heats towards the next target for 3/4 of a timeout */
        for (k = 0; k < 150u; k++) {
            if (tick(1, 0, 0) == GUARD_TIMEOUT) {
                break;
            }
        }
        if (k < 150u) {
            break;
        }
        CHECK(guard_unreached_us() < TIMEOUT_US);
        raised = 0; /* STOP; START: nothing heated since */
        for (k = 0; k < 50u; k++) {
            CHECK_EQ(tick(0, 0, 0), GUARD_OK);
        }
        guard_started();
        run++;
    }
    CHECK_EQ(run, 1u); /* 150 ms a run, 200 ms the timeout: the second run */
    CHECK_EQ(guard_suspect(), 1);
}

/* The coil heated on the way to a target reached made progress: its time starts again. */
static void test_a_coil_that_heated_on_the_way_to_a_target_reached_starts_afresh(void)
{
    uint32_t k, r;
    setup(0);
    raised = 0x02u;
    for (r = 0; r < 5u; r++) { /* 150 ms heated each step, every step reached */
        for (k = 0; k < 150u; k++) {
            CHECK_EQ(tick(1, 0, 0), GUARD_OK);
        }
        CHECK_EQ(tick(1, 1, 0), GUARD_OK);
    }
    /* heating before a START is not progress in it */
    for (k = 0; k < 150u; k++) {
        CHECK_EQ(tick(1, 0, 0), GUARD_OK);
    }
    guard_started();
    raised = 0;
    CHECK_EQ(tick(0, 1, 0), GUARD_OK);
    raised = 0x02u;
    /* every interval it heated while a target was demanded counts: the 150 before the START,
     * the last of them charged in the START's tick, which demands nothing */
    CHECK_EQ(demand_until(GUARD_TIMEOUT, CFG_TICK_US), TIMEOUT_US - 150u * CFG_TICK_US);
    CHECK_EQ(guard_suspect(), 1);
    guard_ack(); /* the operator acknowledged: every coil's time starts again */
    CHECK_EQ(demand_until(GUARD_TIMEOUT, CFG_TICK_US), TIMEOUT_US);
}

/* The interval before a STOP was heated towards the target demanded then: the STOP's tick,
 * which demands nothing, still charges it (each restart of a gait past a dead coil lost one
 * tick, and R1 restarted every 3 s heated its dead coil 8.003 s between latched faults). */
static void test_the_interval_before_a_stop_counts_for_the_coil_that_heated_in_it(void)
{
    uint32_t k, r;
    setup(0);
    raised = 0x02u;
    for (r = 0; r < 2u; r++) {
        for (k = 0; k < 50u; k++) {
            CHECK_EQ(tick(1, 0, 0), GUARD_OK); /* heated and demanded */
        }
        raised = 0;
        CHECK_EQ(tick(0, 0, 0), GUARD_OK); /* STOP: the 50th interval is charged here */
        guard_started();
        raised = 0x02u;
    }
    CHECK_EQ(demand_until(GUARD_TIMEOUT, CFG_TICK_US), TIMEOUT_US - 100u * CFG_TICK_US);
}

/* Time not demanding (STOP, a final hold) is not time without progress. */
static void test_a_coil_heated_while_nothing_is_demanded_does_not_time_out(void)
{
    uint32_t k;
    setup(0);
    raised = 0x01u;
    for (k = 0; k < 100u * CFG_STATE_TIMEOUT_MS; k++) {
        CHECK_EQ(tick(0, 0, 0), GUARD_OK);
    }
}

/* The latch names the coil heated longest without progress among those that hit, not the
 * one that hit last (a healthy coil at a weak supply hitting once on its way up). */
static void test_the_latch_names_the_coil_that_heated_longest_without_progress(void)
{
    uint8_t k;
    setup(0);
    raised = 0x03u;
    CHECK_EQ(tick(1, 0, 0), GUARD_OK);
    raised = 0x02u; /* the dead coil heats on */
    for (k = 0; k < 100u; k++) {
        CHECK_EQ(tick(1, 0, 0), GUARD_OK);
    }
    for (k = 1; k < CFG_ON_LIMIT_LATCH; k++) {
        CHECK_EQ(tick(1, 0, 0x02), GUARD_OK);
    }
    CHECK_EQ(tick(1, 0, 0x01), GUARD_ON_LIMIT);
    CHECK_EQ(act, 1);
}

/* A step that times out with no coil heated (limbs that would not fall, say, in a hot
 * enclosure) suspects no coil: not coil 0, whose limb drive.c would then name over the last
 * limb off its level. A coil that hit in the tick is suspected even with no time. */
static void test_with_no_coil_heated_and_none_hit_no_coil_is_suspected(void)
{
    setup(0);
    raised = 0;
    CHECK_EQ(demand_until(GUARD_TIMEOUT, CFG_TICK_US), TIMEOUT_US);
    CHECK_EQ(guard_suspect(), GUARD_NO_SUSPECT);
    guard_ack();
    CHECK_EQ(tick(1, 0, 0x02), GUARD_OK);
    CHECK_EQ(guard_suspect(), 1);
    CHECK_EQ(tick(1, 0, 0), GUARD_OK);
    CHECK_EQ(guard_suspect(), GUARD_NO_SUSPECT);
    raised = 0x01u;
    CHECK_EQ(tick(1, 0, 0), GUARD_OK);
    CHECK_EQ(tick(1, 0, 0), GUARD_OK);
    CHECK_EQ(guard_suspect(), 0);
}

int main(void)
{
    RUN(test_an_unreached_target_times_out_on_real_time);
    RUN(test_the_timeout_is_right_across_the_clock_wrap_and_with_slow_ticks);
    RUN(test_time_not_demanding_does_not_count_but_a_restart_does_not_reset_it);
    RUN(test_past_the_timeout_a_tick_not_demanding_is_ok);
    RUN(test_reaching_a_target_starts_the_next_step_afresh);
    RUN(test_repeated_on_limit_hits_without_progress_latch);
    RUN(test_hits_on_different_steps_do_not_latch);
    RUN(test_hits_latch_when_only_other_coils_lift_their_limbs_in_between);
    RUN(test_with_no_time_without_progress_the_latch_names_the_coil_that_hit);
    RUN(test_hits_reset_once_every_coil_that_hit_has_heated_on_the_way_to_a_target);
    RUN(test_heating_decided_in_the_tick_of_a_reach_is_no_progress_to_it);
    RUN(test_the_operator_acknowledging_a_fault_restarts_the_step_time);
    RUN(test_a_narrowed_timeout_applies_and_a_wider_one_counts_as_the_build_value);
    RUN(test_a_coil_that_heats_across_restarts_and_never_progresses_times_out);
    RUN(test_a_coil_that_heated_on_the_way_to_a_target_reached_starts_afresh);
    RUN(test_the_interval_before_a_stop_counts_for_the_coil_that_heated_in_it);
    RUN(test_a_coil_heated_while_nothing_is_demanded_does_not_time_out);
    RUN(test_the_latch_names_the_coil_that_heated_longest_without_progress);
    RUN(test_with_no_coil_heated_and_none_hit_no_coil_is_suspected);
    return UNIT_EXIT();
}
