/* param.c - see param.h. */
#include "param.h"

#include "proto.h"
#include "psi.h"
#include "rom.h"
#include "safety.h"
#include "seq.h"
#include "sma.h"

#define ANY INT32_MAX
#define MAX_PARAM_MS 600000L

typedef struct {
    uint16_t drive_pm, hold_pm;
    uint32_t max_on_ticks, cooldown_ticks;
    uint32_t watchdog_us; /* the link watchdog, in ticks of CFG_TICK_US as set, µs */
} param_st_t;
static param_st_t st;

/* ceil(ms * CFG_TICK_HZ / 1000), ms ≤ INT32_MAX (param_set's ranges). */
static uint32_t ms_to_ticks(uint32_t ms)
{
#if 1000u % CFG_TICK_HZ == 0u
    /* a whole number K of ms per tick (1, 2, 4, 5 ... ms): ceil(ms / K), the same value
     * without the 32-bit divisions by 1000 (+ K - 1 cannot wrap: ms ≤ INT32_MAX) */
    return (ms + (1000u / CFG_TICK_HZ - 1u)) / (1000u / CFG_TICK_HZ);
#else
    return (ms / 1000u) * CFG_TICK_HZ + ((ms % 1000u) * CFG_TICK_HZ + 999u) / 1000u;
#endif
}

/* ---- where each parameter lives: v is in range and scaled; 0 or a PROTO_ERR_* code */

/* A duty (permyriad) into *dst, at most the ceiling in force. */
#if defined(__GNUC__)
__attribute__((noinline)) /* two callers: one copy */
#endif
static uint8_t set_duty(uint16_t *dst, int32_t v)
{
    if (v > (int32_t)sma_max_duty()) {
        return PROTO_ERR_SAFETY_LIMIT;
    }
    *dst = (uint16_t)v;
    return 0;
}

static uint8_t set_drive_duty(uint8_t index, int32_t v)
{
    (void)index;
    return set_duty(&st.drive_pm, v);
}

static uint8_t set_hold_duty(uint8_t index, int32_t v)
{
    (void)index;
    return set_duty(&st.hold_pm, v);
}

static uint8_t set_hold(uint8_t index, int32_t ticks)
{
    (void)index;
    seq_set_hold((uint32_t)ticks);
    return 0;
}

static uint8_t set_debounce(uint8_t index, int32_t v)
{
    (void)index;
    psi_set_debounce((uint16_t)v);
    return 0;
}

static uint8_t set_timeout(uint8_t index, int32_t ticks)
{
    (void)index;
    seq_set_timeout((uint32_t)ticks);
#if CFG_TICK_US % 1000u == 0u
    guard_set_timeout_ms((uint32_t)ticks * (CFG_TICK_US / 1000u)); /* safety: the real-time timeout */
#else
    guard_set_timeout_ms((uint32_t)ticks * CFG_TICK_US / 1000u); /* safety: the real-time timeout */
#endif
    return 0;
}

/* Where threshold `flat` (limb by limb, thresholds in order) lives. */
static int8_t threshold_at(uint8_t flat, uint8_t *limb, uint8_t *thr)
{
#if PSI_UNIFORM_LEVELS && CFG_MAX_LEVELS == 2u
    /* every limb has 2 levels, one threshold: threshold `flat` is limb `flat`'s (the loop below
     * with each n = 1, without it) */
    *limb = flat;
    *thr = 0;
    return flat < CFG_N_LIMBS ? 0 : -1;
#else
    uint8_t i;
    for (i = 0; i < CFG_N_LIMBS; i++) {
        uint8_t n = (uint8_t)(psi_levels(i) - 1u);
        if (flat < n) {
            *limb = i;
            *thr = flat;
            return 0;
        }
        flat = (uint8_t)(flat - n);
    }
    return -1;
#endif
}

static uint8_t set_psi_star(uint8_t index, int32_t v)
{
    uint8_t limb, thr;
    if (threshold_at(index, &limb, &thr) != 0 ||
        psi_set_band(limb, thr, (int16_t)v, psi_hyst_cdeg(limb, thr)) != 0) {
        return PROTO_ERR_OUT_OF_RANGE;
    }
    return 0;
}

static uint8_t set_hysteresis(uint8_t index, int32_t v)
{
    return psi_set_hysteresis(index, (int16_t)v) != 0 ? PROTO_ERR_OUT_OF_RANGE : 0u; /* all bands or none */
}

/* On-time and cool-down (ticks) into the envelope, which refuses to widen it. */
#if defined(__GNUC__)
__attribute__((noinline)) /* two callers: one copy */
#endif
static uint8_t set_on_times(uint32_t max_on_ticks, uint32_t cooldown_ticks)
{
    int8_t r = sma_set_limits(sma_max_duty(), max_on_ticks, cooldown_ticks);
    if (r != 0) {
        return r == -1 ? PROTO_ERR_SAFETY_LIMIT : PROTO_ERR_OUT_OF_RANGE; /* -2: a cool-down of 256 on-times */
    }
    st.max_on_ticks = max_on_ticks;
    st.cooldown_ticks = cooldown_ticks;
    return 0;
}

static uint8_t set_max_on(uint8_t index, int32_t ticks)
{
    (void)index;
    return set_on_times((uint32_t)ticks, st.cooldown_ticks);
}

static uint8_t set_cooldown(uint8_t index, int32_t ticks)
{
    (void)index;
    return set_on_times(st.max_on_ticks, (uint32_t)ticks);
}

static uint8_t set_watchdog(uint8_t index, int32_t ticks)
{
    (void)index;
    st.watchdog_us = (uint32_t)ticks * CFG_TICK_US; /* ≤ 600 s: fits */
    return 0;
}

/* ---- the table */

#define AS_IS 0u
#define MS 1u /* value in ms, applied in ticks (rounded up) */

/* Every bound a row names, once (a row holds their numbers: 7 bytes a row, not 19). */
#if CFG_LINK_WATCHDOG_MS != 0
#define WATCHDOG_SAFE_MIN 1 /* a build with a watchdog cannot turn it off */
#define WATCHDOG_SAFE_MAX ((int32_t)CFG_LINK_WATCHDOG_MS)
#else
#define WATCHDOG_SAFE_MIN 0
#define WATCHDOG_SAFE_MAX ANY
#endif
enum { B_0, B_1, B_ANY, B_MAX_MS, B_1000, B_2000, B_M8999, B_8999, B_TIMEOUT, B_MAX_ON, B_COOLDOWN, B_WD_MIN, B_WD_MAX, B_HOLD };
static const int32_t bounds[] ROM = {
    [B_0] = 0, [B_1] = 1, [B_ANY] = ANY, [B_MAX_MS] = MAX_PARAM_MS, [B_1000] = 1000, [B_2000] = 2000,
    [B_M8999] = -8999, [B_8999] = 8999, [B_TIMEOUT] = (int32_t)CFG_STATE_TIMEOUT_MS, [B_MAX_ON] = (int32_t)CFG_MAX_ON_MS,
    [B_COOLDOWN] = (int32_t)CFG_MIN_COOLDOWN_MS, [B_WD_MIN] = WATCHDOG_SAFE_MIN, [B_WD_MAX] = WATCHDOG_SAFE_MAX,
#ifdef CFG_LIMB_STROKE_CDEG
    [B_HOLD] = (int32_t)CFG_HOLD_MAX_DUTY_PM,
#endif
};

/* safety: the hold duty a host may set. A stroke build keeps a spent coil (the knee watch,
 * ctl.c) and every limb waiting in a climb at the hold duty, trusting it to be a duty the coil
 * may carry for ever: at most the hold ceiling. Up to max_duty, ψ* 70° and a hold duty of 0.4
 * pre-warmed R1's left coil past its transformation, so the knee watch never saw a fast window,
 * and the drive duty took it to 133 °C every cycle (9 s of 120 above 120 °C, no fault). Other
 * builds keep max_duty (R1's Nano image has no 4 bytes to spare); docs/safety.md. */
#ifdef CFG_LIMB_STROKE_CDEG
#define B_HOLD_SAFE B_HOLD
#else
#define B_HOLD_SAFE B_ANY
#endif

typedef struct {
    uint8_t scale;              /* AS_IS or MS */
    uint8_t min, max;           /* outside: OUT_OF_RANGE (B_*) */
    uint8_t safe_min, safe_max; /* outside: SAFETY_LIMIT, the build's envelope (B_*) */
    uint8_t (*apply)(uint8_t index, int32_t v);
} param_desc_t;

/* Indexed by id - 1 (ids start at 1: no empty row 0). */
#define ROW(id) [PROTO_PARAM_##id - 1]
static const param_desc_t table[] ROM = {
    /* id                     scale  min   max       safe_min    safe_max */
    ROW(DRIVE_DUTY) = {AS_IS, B_1, B_ANY, B_0, B_ANY, set_drive_duty}, /* ≤ sma_max_duty() */
    ROW(HOLD_DUTY) = {AS_IS, B_0, B_ANY, B_0, B_HOLD_SAFE, set_hold_duty}, /* ≤ sma_max_duty() */
    ROW(HOLD_MS) = {MS, B_0, B_MAX_MS, B_0, B_ANY, set_hold},
    ROW(DEBOUNCE_TICKS) = {AS_IS, B_1, B_1000, B_0, B_ANY, set_debounce},
    ROW(STATE_TIMEOUT_MS) = {MS, B_1, B_ANY, B_0, B_TIMEOUT, set_timeout},
    ROW(PSI_STAR_CDEG) = {AS_IS, B_M8999, B_8999, B_M8999, B_ANY, set_psi_star},
    ROW(HYSTERESIS_CDEG) = {AS_IS, B_0, B_2000, B_0, B_ANY, set_hysteresis},
    ROW(MAX_ON_MS) = {MS, B_1, B_ANY, B_0, B_MAX_ON, set_max_on},
    ROW(MIN_COOLDOWN_MS) = {MS, B_0, B_MAX_MS, B_COOLDOWN, B_ANY, set_cooldown},
    ROW(LINK_WATCHDOG_MS) = {MS, B_0, B_MAX_MS, B_WD_MIN, B_WD_MAX, set_watchdog},
};

#if defined(__GNUC__)
__attribute__((noinline)) /* four uses: one copy */
#endif
static int32_t bound(uint8_t b)
{
    return (int32_t)ROM_U32(&bounds[b]);
}

uint8_t param_set(uint8_t param, uint8_t index, int32_t v)
{
    param_desc_t d;
    param = (uint8_t)(param - 1u); /* 0 wraps to 255: out of range */
    if (param >= sizeof table / sizeof table[0]) {
        return PROTO_ERR_OUT_OF_RANGE;
    }
    ROM_COPY(&d, &table[param], sizeof d);
    if (d.apply == 0 || v < bound(d.min) || v > bound(d.max)) {
        return PROTO_ERR_OUT_OF_RANGE;
    }
    if (v < bound(d.safe_min) || v > bound(d.safe_max)) {
        return PROTO_ERR_SAFETY_LIMIT;
    }
    if (d.scale == MS) {
        v = (int32_t)ms_to_ticks((uint32_t)v);
    }
    return d.apply(index, v);
}

/* The build's values, copied as one block: on AVR 16 B of flash where storing each
 * constant took 68 B of code (issue 11). */
static const param_st_t st_init ROM = {
    CFG_DRIVE_DUTY_PM, CFG_HOLD_DUTY_PM, CFG_MAX_ON_TICKS, CFG_MIN_COOLDOWN_TICKS,
    CFG_LINK_WATCHDOG_TICKS * CFG_TICK_US,
};

void param_init(void)
{
    ROM_COPY(&st, &st_init, sizeof st);
}

uint16_t param_drive_pm(void)
{
    return st.drive_pm;
}

uint16_t param_hold_pm(void)
{
    return st.hold_pm;
}

uint32_t param_watchdog_us(void)
{
    return st.watchdog_us;
}
