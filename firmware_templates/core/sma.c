/* sma.c - see sma.h. */
#include "sma.h"

#include <string.h>

#include "elapsed.h"
#include "hal.h"
#include "initzero.h"
#include "rom.h"

#if CFG_DUTY_WINDOW_MS < 8UL || CFG_DUTY_WINDOW_MS > 600000UL
#error "duty_window_ms must lie in 8 .. 600000"
#endif

/* The mean-duty window as SMA_WIN_SLOTS ring slots of CFG_DUTY_WINDOW_MS / 8 each plus the
 * slot being filled: their sum covers between 1 and 9/8 windows, so a limit on the sum is a
 * limit on every window of CFG_DUTY_WINDOW_MS (conservative by at most one slot). */
#define SMA_WIN_SLOTS 9u
#define SMA_SLOT_US (CFG_DUTY_WINDOW_MS * 1000UL / (SMA_WIN_SLOTS - 1u))
/* Window sums count permyriad × µs / 1024. */
#define SMA_WIN_LIMIT ((uint32_t)CFG_MEAN_DUTY_PM * ((CFG_DUTY_WINDOW_MS * 1000UL) >> 10))
/* The longest interval elapsed_us returns (elapsed.h): the cap, or one tick for a backwards step. */
#define SMA_DT_MAX (ELAPSED_CAP_US > CFG_TICK_US ? ELAPSED_CAP_US : (uint32_t)CFG_TICK_US)
#define SMA_TICK_CHARGE(d) (((uint32_t)(d) * CFG_TICK_US + 1023UL) >> 10)

static const uint8_t act_channel[CFG_N_ACTUATORS] ROM = CFG_ACTUATOR_CHANNELS;

typedef struct {
    uint32_t debt_us;  /* on-time not yet paid back by cool-down */
    uint16_t win_rem;  /* remainder of the last charge, below 1024 */
    uint16_t request;  /* wanted duty */
    uint16_t applied;  /* last output (0 after all_off/estop) */
    uint16_t charged;  /* duty the pin carried since the last tick: charged at the next */
    uint8_t blocked;   /* the mean-duty window refused the last request */
    uint8_t forced;    /* cut at max_on: fully off until the debt is paid */
    uint8_t pay_rem;   /* the pay-back's fraction of a µs (× 256) carried to the next tick */
#ifdef CFG_COIL_TAU_MS
    int32_t heat;      /* the duty the pin carried, smoothed with the coil's time constant (pm × 256) */
#endif
} act_state_t;

/* What the envelope keeps across a reset that is not a power-on (a Nano's DTR auto-reset, a
 * brown-out, the watchdog, the reset button): every coil's unpaid on-time and heat, its
 * mean-duty window and where the window is. Otherwise each reset started every coil cold,
 * and a host that reconnected (which resets a Nano) and STARTed at once heated a coil the
 * envelope had just cut as if it had rested (docs/safety.md, "A reset"). The time the reset
 * took counts as none: the coil is taken to have cooled no further. `mark` says this build
 * set the rest: RAM after a power-on, or after another image ran, is not trusted. */
typedef struct {
    act_state_t acts[CFG_N_ACTUATORS];
    uint32_t win[SMA_WIN_SLOTS][CFG_N_ACTUATORS];
    uint32_t slot_us;   /* time in the slot being filled */
    uint8_t slot;       /* the slot being filled */
    uint8_t estopped;   /* an E-stop latched: a reset does not release it, CLEAR does */
    uint16_t mark;      /* SMA_KEPT_MARK once sma_init has cleared the rest */
} sma_kept_t;
#define SMA_KEPT_MARK ((uint16_t)(CFG_BUILD_ID ^ (CFG_BUILD_ID >> 16) ^ 0x5AA5u))
static sma_kept_t kept NOINIT;
static uint32_t last_us;
/* What sma_init sets, in one record it copies from one ROM block (no .data bytes in flash;
 * on AVR a 16 B block and one copy call instead of storing each value: R1 66 B smaller on
 * the Nano, issue 11). */
typedef struct {
    uint32_t max_on_us; /* the limits in force (SET_PARAM may narrow them) */
    uint16_t max_duty;
    uint16_t refill_q8; /* on-time paid back per µs of cool-down, × 256, rounded down; ≤ 10000 */
} sma_vars_t;
static sma_vars_t st;
static uint8_t clamped;
/* Variables, not the macros: comparing against a constant 0 would warn (-Wtype-limits). */
static const uint32_t min_cooldown = CFG_MIN_COOLDOWN_TICKS;
static const uint16_t hold_max = CFG_HOLD_MAX_DUTY_PM;

#if defined(__GNUC__)
__attribute__((noinline)) /* four callers: one copy on the 8-bit targets */
#endif
uint16_t sma_clamp(uint16_t duty_pm)
{
    uint16_t ceiling = st.max_duty < CFG_MAX_DUTY_PM ? st.max_duty : (uint16_t)CFG_MAX_DUTY_PM;
    return duty_pm > ceiling ? ceiling : duty_pm;
}

/* The only call of hal_pwm_set for actuators. Its one caller, sma_tick, passes 0 or a duty
 * it clamped (and counted) already in this call, and a clamped duty clamps to itself: no
 * clamp again here (R1 18 B smaller on the Nano). */
static void output(uint8_t act, uint16_t duty_pm)
{
    kept.acts[act].applied = duty_pm;
    kept.acts[act].charged = duty_pm;
    hal_pwm_set(ROM_U8(&act_channel[act]), duty_pm);
}

/* Pins off now. `charged` keeps the duty the pin had: the time until the next sma_tick is
 * charged at it, so stopping between two ticks never shortens an on-period. */
static void every_channel_off(void)
{
    uint8_t ch;
    uint8_t i;
    for (ch = 0; ch < CFG_PWM_CHANNELS; ch++) {
        hal_pwm_set(ch, 0);
    }
    for (i = 0; i < CFG_N_ACTUATORS; i++) {
        kept.acts[i].request = 0;
        kept.acts[i].applied = 0;
    }
}

/* Cool-down pays back max_on / min_cooldown µs of on-time per µs, i.e. an on-period of L
 * is paid back by L × min_cooldown / max_on of cool-down. The rate is rounded down to
 * 1/256 (and at most 39×: a min_cooldown below 1/39 of max_on counts as 1/39): paid back no
 * faster than that; below 1/256 it would be 0, so such a cool-down is refused. */
#define REFILL_QUOT(on_us, cooldown_us) ((on_us) / (((cooldown_us) >> 8) + 1u))
#define REFILL_Q8_OF(q) ((uint16_t)((q) > 10000u ? 10000u : (q))) /* the rate from REFILL_QUOT's q */
#define REFILL_Q8(on_us, cooldown_us) REFILL_Q8_OF(REFILL_QUOT(on_us, cooldown_us))

/* At start: the build's limits (what sma_set_limits makes of its max_on and min_cooldown), no
 * ESTOP. */
#define SMA_ON_US ((uint32_t)(CFG_MAX_ON_TICKS * CFG_TICK_US))
#define SMA_COOLDOWN_US ((uint32_t)(CFG_MIN_COOLDOWN_TICKS * CFG_TICK_US))
static const sma_vars_t st_init ROM = {SMA_ON_US, CFG_MAX_DUTY_PM, REFILL_Q8(SMA_ON_US, SMA_COOLDOWN_US)};
/* The build's own limits pay back (robot_settings.py refuses a min_cooldown_ms of 256 × max_on_ms or
 * more; this makes a hand-edited config fail to compile rather than lock every coil off). */
typedef char sma_build_cooldown_pays_back[REFILL_QUOT(SMA_ON_US, SMA_COOLDOWN_US) > 0u ? 1 : -1];

/* Move the window on by dt: slots older than the window fall out. */
static void advance_window(uint32_t dt)
{
    uint8_t i;
    /* elapsed_us returns at most SMA_DT_MAX: the test is compiled only where a window is shorter */
    if (SMA_DT_MAX > SMA_SLOT_US * SMA_WIN_SLOTS && dt > SMA_SLOT_US * SMA_WIN_SLOTS) {
        dt = SMA_SLOT_US * SMA_WIN_SLOTS;
    }
    /* slot_us < one slot before, so below SMA_WIN_SLOTS + 1 slots now: at most
     * SMA_WIN_SLOTS slots fall out, each cleared once */
    kept.slot_us += dt;
    while (kept.slot_us >= SMA_SLOT_US) {
        kept.slot_us -= SMA_SLOT_US;
        if (++kept.slot >= SMA_WIN_SLOTS) { /* in 8 bits (issue 11) */
            kept.slot = 0;
        }
        for (i = 0; i < CFG_N_ACTUATORS; i++) {
            kept.win[kept.slot][i] = 0;
        }
    }
}

/* Actuator `act`'s window: the sum of its slots, the value a running total of them would
 * hold (added to with each charge, reduced as a slot falls out). Summed when needed rather
 * than kept: the running total's bookkeeping cost more flash than nine additions (issue 11). */
static uint32_t window_sum(uint8_t act)
{
    uint32_t t = 0;
    uint8_t k;
    for (k = 0; k < SMA_WIN_SLOTS; k++) {
        t += kept.win[k][act];
    }
    return t;
}

uint8_t sma_init(uint8_t warm)
{
    /* the slot indexes the window: one out of range is RAM this build did not leave */
    if (!warm || kept.mark != SMA_KEPT_MARK || kept.slot >= SMA_WIN_SLOTS) {
        memset(&kept, 0, sizeof kept);
        kept.mark = SMA_KEPT_MARK;
        warm = 0;
    }
#ifdef CFG_COIL_TAU_MS
    else {
        /* a heat is a smoothed duty: one outside 0 .. 100 % is noise that matched the mark (and
         * would overflow heat_step): taken as hot as can be */
        uint8_t i;
        for (i = 0; i < CFG_N_ACTUATORS; i++) {
            if ((uint32_t)kept.acts[i].heat > (10000UL << 8)) {
                kept.acts[i].heat = (int32_t)10000L << 8;
            }
        }
    }
#endif
    last_us = hal_micros();
    ROM_COPY(&st, &st_init, sizeof st);
    every_channel_off();
    return warm;
}

void sma_request(uint8_t act, uint16_t duty_pm)
{
    if (act < CFG_N_ACTUATORS) {
        kept.acts[act].request = duty_pm;
    }
}

static uint8_t heated; /* a bit per channel heated above the hold ceiling since sma_take_heated */

#ifdef CFG_COIL_TAU_MS
/* The coil's heat (sma.h): a first-order coil's temperature rise is its duty smoothed with the
 * coil's own time constant CFG_COIL_TAU_MS (heat capacity / conductance to the air), times the
 * rise a full duty settles at. Smoothed here as heat += (duty - heat) × dt / tau, dt / tau in
 * 1/65536 from one 32-bit multiply. A coil whose
 * smoothed duty has reached the mean-duty ceiling is as hot as that ceiling held for ever (what
 * the envelope already lets it settle at, and what `proleg sim` warns of past 120 °C): it gets at
 * most that ceiling, which keeps it there, whatever STOP, START or SET_PARAM did in between
 * (docs/safety.md, "The coil's heat ceiling"). At the ceiling rather than the hold ceiling: a
 * coil weaker than the nominal one (its heat overstates it) creeps on through its
 * transformation; and no alternation between two duties tick by tick. Built only where the robot
 * file opts in ([safety] coil_heat_ceiling = true): it takes every coil for the nominal one. */
/* 2^32 / tau in µs, rounded up; dt × it < 2^32 for every dt elapsed_us returns (tau > 0.4 s) */
#define SMA_HEAT_K (0xFFFFFFFFUL / (CFG_COIL_TAU_MS * 1000UL) + 1u)
typedef char sma_heat_fits[SMA_HEAT_K < 0xFFFFFFFFUL / SMA_DT_MAX ? 1 : -1];

static uint16_t heat_step(act_state_t *a, uint32_t dt)
{
    int32_t f = (int32_t)((dt * SMA_HEAT_K) >> 16); /* dt / tau in 1/65536, ≤ 65535 */
    int32_t d = ((int32_t)a->charged << 8) - a->heat;
    a->heat += ((d >> 8) * f) >> 8;
    /* at the ceiling: the duty that keeps it there (its steady state), never more */
    return a->heat >= ((int32_t)CFG_MEAN_DUTY_PM << 8) ? (uint16_t)CFG_MEAN_DUTY_PM : 0xFFFFu;
}
#endif

uint8_t sma_take_heated(void)
{
    uint8_t h = heated;
    heated = 0;
    return h;
}

uint8_t sma_tick(uint8_t holding)
{
    uint32_t dt = elapsed_us(&last_us); /* wrap-safe; a backwards step or a stall capped */
    uint8_t hit = 0;
    uint8_t i, bit, blocked;
    uint32_t *w;
    advance_window(dt);
    w = kept.win[kept.slot];
    for (i = 0, bit = 1u; i < CFG_N_ACTUATORS; i++, bit = (uint8_t)(bit << 1)) {
        act_state_t *a = &kept.acts[i];
        uint16_t duty = kept.estopped ? 0u : sma_clamp(a->request);
        uint32_t x = (uint32_t)a->charged * dt + a->win_rem; /* ≤ 10000 × 400000 + 1023 */
        if (!kept.estopped && duty != a->request) {
            clamped = 1;
        }
        /* charge the interval since the last tick at the duty the pin carried */
        w[i] += x >> 10;
        a->win_rem = (uint16_t)(x & 1023u);
        if (a->charged > hold_max) {
            a->debt_us += dt; /* ≤ max_on + SMA_DT_CAP_US: on-time is cut at max_on */
            a->pay_rem = 0;
        } else {
            /* ≤ 400000 × 10000 + 255: 32 × 16 bits, no 32 × 32 multiply. The fraction carries
             * on, so a fast tick pays back at the rate set, not at its rounding (at 10 kHz a
             * rate below 2.56/256 would round to nothing every tick). */
            uint32_t y = dt * st.refill_q8 + a->pay_rem;
            uint32_t paid = y >> 8;
            a->pay_rem = (uint8_t)(y & 255u);
            a->debt_us = a->debt_us > paid ? a->debt_us - paid : 0u;
            if (a->debt_us == 0u) {
                a->forced = 0;
                a->pay_rem = 0;
            }
        }
#ifdef CFG_COIL_TAU_MS
        /* as hot as the mean-duty ceiling held for ever: that ceiling at most */
        {
            uint16_t most = heat_step(a, dt);
            if (duty > most) {
                duty = most;
            }
        }
#endif
        /* then decide the next output */
        if (a->forced) {
            duty = 0; /* cooling after an on-limit hit: off until the debt is paid */
        } else if (duty > hold_max) {
            if (a->debt_us + CFG_TICK_US > st.max_on_us) {
                duty = 0; /* cut before the next tick would pass max_on */
                a->forced = 1;
                hit = (uint8_t)(hit | bit);
            } else {
                /* heats on from now (not charged for what it carried before a STOP + START:
                 * that would credit a dead coil with progress the other coil made, safety.h) */
                heated = (uint8_t)(heated | bit);
            }
        }
        blocked = (uint8_t)(duty > 0u && window_sum(i) + SMA_TICK_CHARGE(duty) > SMA_WIN_LIMIT);
        if (blocked) {
            /* the window stopping a coil that heats a held target (above the hold ceiling) is a
             * hit, once a block: a hold that never reaches its hold edge heated at the mean-duty
             * limit for good, never hitting max_on, with no fault (docs/safety.md) */
            if (holding && !a->blocked && duty > hold_max) {
                hit = (uint8_t)(hit | bit);
            }
            duty = 0;
        }
        a->blocked = blocked;
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
    kept.estopped = 1;
    every_channel_off();
}

void sma_clear_estop(void)
{
    kept.estopped = 0;
}

uint8_t sma_estopped(void)
{
    return kept.estopped;
}

int8_t sma_set_limits(uint16_t max_duty_pm, uint32_t max_on_ticks, uint32_t cooldown_ticks)
{
    uint32_t on_us, q;
    if (max_duty_pm > CFG_MAX_DUTY_PM || max_on_ticks > CFG_MAX_ON_TICKS || cooldown_ticks < min_cooldown ||
        cooldown_ticks > 0xFFFFFFFFUL / CFG_TICK_US) {
        return -1;
    }
    on_us = max_on_ticks * CFG_TICK_US;
    q = REFILL_QUOT(on_us, cooldown_ticks * CFG_TICK_US); /* the one division */
    if (q == 0u) {
        return -2; /* a cool-down of 256 on-times or more would pay back nothing: never again */
    }
    st.max_duty = max_duty_pm;
    st.max_on_us = on_us;
    st.refill_q8 = REFILL_Q8_OF(q);
    return 0;
}

#if defined(__GNUC__)
__attribute__((noinline)) /* smaller out of line (measured) */
#endif
uint16_t sma_max_duty(void)
{
    return sma_clamp(0xFFFFu);
}

uint16_t sma_duty(uint8_t act)
{
    return kept.acts[act].applied;
}

uint8_t sma_cooling(uint8_t act)
{
    return (uint8_t)(kept.acts[act].forced | kept.acts[act].blocked); /* each 0 or 1 */
}

uint32_t sma_debt_us(uint8_t act)
{
    return kept.acts[act].debt_us;
}

uint8_t sma_take_clamped(void)
{
    uint8_t c = clamped;
    clamped = 0;
    return c;
}


