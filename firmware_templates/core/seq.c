/* seq.c - see seq.h. */
#include "seq.h"

#include <string.h>

#include "count.h"
#include "initzero.h"
#include "psi.h"
#include "rom.h"

#if CFG_STATE_BYTES == 1
#define ROM_STATE(p) ((cfg_state_t)ROM_U8(p))
#else
#define ROM_STATE(p) ((cfg_state_t)ROM_U16(p))
#endif

#if defined(__GNUC__)
#define NOINLINE __attribute__((noinline)) /* several callers: one copy on the 8-bit targets */
#else
#define NOINLINE
#endif

/* Variables, not macros, so range checks never compare against a type's limits. At most
 * 65535 states (proleg build refuses more): state numbers compare in 16 bits. */
static const uint16_t n_states = CFG_N_STATES;
/* A robot_config.h rendered before CFG_ENTRY_PATHS existed: the entry-path code stays in. */
#ifndef CFG_ENTRY_PATHS
#define CFG_ENTRY_PATHS 1
#endif
typedef char at_most_65535_states[CFG_N_STATES <= 0xFFFFUL ? 1 : -1];

/* A step's place in a walk: one byte when every rendered gait step and every loadable step
 * is numbered below 255 (an 8-bit MCU then indexes and compares in single bytes). */
#if CFG_N_GAIT_STEPS + CFG_MAX_LOADED_STEPS < 255u
typedef uint8_t step_ix_t;
#define STEP_IX_BYTE 1
#else
typedef uint16_t step_ix_t;
#define STEP_IX_BYTE 0
#endif

static cfg_state_t loaded[CFG_MAX_LOADED_STEPS];
static step_ix_t loaded_n;

static struct {
    uint8_t running;
    uint8_t reached;
    uint8_t dir;
    step_ix_t first; /* offset into seq_steps (rendered gaits) */
    step_ix_t n;     /* steps in the walk */
    step_ix_t step;
    uint32_t step_ticks;
    uint32_t held;
    uint32_t cycles;
#if SEQ_CLOCK_PAUSE
    uint8_t paused; /* seq_pause_clock */
#endif
#if CFG_ENTRY_PATHS
    uint16_t entry_at;   /* next entry state in seq_entry_steps */
    uint16_t entry_left; /* entry states still to reach before the gait's join step */
#endif
} s;
#if CFG_ENTRY_PATHS
#define ENTRY_LEFT s.entry_left
#else
#define ENTRY_LEFT 0u /* every rendered gait is entered from rest at its step 0: never on an entry path */
#endif

/* Both set by seq_init (no .data bytes in flash), from one ROM block: on AVR 8 B of flash
 * and a copy call where storing the two 32-bit constants took 48 B of code (R1 24 B smaller
 * on the Nano, issue 11). */
typedef struct {
    uint32_t hold, timeout; /* ticks a target is held before the next step; a step's timeout */
} seq_ticks_t;
static seq_ticks_t ticks;
static const seq_ticks_t ticks_init ROM = {CFG_HOLD_TICKS, CFG_STATE_TIMEOUT_TICKS};

/* A new step: nothing held, not reached, its time from 0. */
static NOINLINE void new_step(void)
{
    s.step_ticks = 0;
    s.held = 0;
    s.reached = 0;
}

void seq_init(void)
{
    INIT_ZERO(s); /* not running, no walk */
    INIT_ZERO(loaded_n);
    ROM_COPY(&ticks, &ticks_init, sizeof ticks);
}

#if SEQ_CLOCK_PAUSE
void seq_pause_clock(uint8_t paused)
{
    s.paused = paused;
}
#endif

void seq_set_hold(uint32_t n)
{
    ticks.hold = n;
}

void seq_set_timeout(uint32_t n)
{
    ticks.timeout = n;
}

uint8_t seq_allowed_transition(cfg_state_t a, cfg_state_t b)
{
#if CFG_N_STATES <= 16u
    uint8_t key; /* < 16²: one byte on the 8-bit targets */
#elif CFG_N_STATES <= 256u
    uint16_t key; /* < 256², and no 32-bit multiply on the 8-bit targets */
#else
    uint32_t key;
#endif
    if (a >= n_states || b >= n_states || a == b) {
        return 0;
    }
#if CFG_N_STATES <= 16u
    key = (uint8_t)((uint16_t)a * (uint16_t)n_states + b);
#elif CFG_N_STATES <= 256u
    key = (uint16_t)((uint16_t)a * (uint16_t)n_states + b);
#else
    key = (uint32_t)a * n_states + b;
#endif
#if CFG_TRANS_BITMAP
    return (uint8_t)((ROM_U8(&seq_allowed[key >> 3]) >> (key & 7u)) & 1u);
#else
    {
        /* Sorted keys: binary search, no recursion. */
        uint32_t lo = 0, hi = CFG_N_TRANSITIONS;
        while (lo < hi) {
            uint32_t mid = lo + (hi - lo) / 2u;
            uint32_t k = ROM_U32(&seq_edges[mid]);
            if (k == key) {
                return 1;
            }
            if (k < key) {
                lo = mid + 1u;
            } else {
                hi = mid;
            }
        }
        return 0;
    }
#endif
}

uint8_t seq_gait_count(uint8_t dir)
{
    if (dir == SEQ_DIR_PX) {
        return CFG_N_GAITS_PX;
    }
    if (dir == SEQ_DIR_MX) {
        return CFG_N_GAITS_MX;
    }
    return loaded_n ? 1u : 0u;
}

int8_t seq_load(const cfg_state_t *states, uint16_t count, uint16_t *bad)
{
    step_ix_t i, n; /* n ≤ CFG_MAX_LOADED_STEPS once checked: a step_ix_t */
    int8_t err = SEQ_ERR_STATE;
    if (count >= 2u && states[count - 1u] == states[0]) {
        count--; /* closed form */
    }
    /* one state left is checked as a walk too: it follows itself, the forbidden transition
     * LOAD_GAIT documents at step 0 (10 10 used to be refused as too short, OUT_OF_RANGE) */
    if (count == 0u || count > CFG_MAX_LOADED_STEPS) {
        return SEQ_ERR_LENGTH;
    }
    n = (step_ix_t)count;
    for (i = 0; i < n; i++) {
        if (states[i] >= n_states) {
            goto refused;
        }
    }
    err = SEQ_ERR_FORBIDDEN;
    for (i = 0; i < n; i++) {
        cfg_state_t next = states[(step_ix_t)(i + 1u) == n ? 0u : (step_ix_t)(i + 1u)];
        if (!seq_allowed_transition(states[i], next)) {
            goto refused;
        }
    }
    if (s.running && s.dir == SEQ_DIR_LOADED) {
        s.running = 0; /* never run a half-replaced walk */
    }
    memcpy(loaded, states, n * sizeof loaded[0]);
    loaded_n = n;
    return SEQ_OK;
refused: /* one exit for both refusals (issue 11: one copy of the store) */
    if (bad) {
        *bad = i;
    }
    return err;
}

static cfg_state_t step_state(step_ix_t step)
{
    if (s.dir == SEQ_DIR_LOADED) {
        return loaded[step];
    }
    return ROM_STATE(&seq_steps[s.first + step]);
}

/* Out of line: seq_target and seq_tick share one copy (the tick inlines seq_tick right after
 * its seq_target call; R1 on the Nano 36 B smaller). */
static NOINLINE cfg_state_t target_state(void)
{
#if CFG_ENTRY_PATHS
    return s.entry_left ? ROM_STATE(&seq_entry_steps[s.entry_at]) : step_state(s.step);
#else
    return step_state(s.step);
#endif
}

int8_t seq_start(uint8_t dir, uint8_t index, uint16_t measured)
{
    step_ix_t i;
    uint16_t g = 0; /* g: the rendered gait's row in the tables */
    if (dir == SEQ_DIR_LOADED) {
        if (loaded_n == 0u || index != 0u) {
            return SEQ_ERR_NO_GAIT;
        }
        s.first = 0;
        s.n = loaded_n;
    } else {
        if (dir > SEQ_DIR_MX || index >= seq_gait_count(dir)) {
            return SEQ_ERR_NO_GAIT;
        }
        g = (uint16_t)(dir == SEQ_DIR_PX ? index : CFG_N_GAITS_PX + index);
        s.first = (step_ix_t)ROM_U16(&seq_gait_first[g]);
        s.n = (step_ix_t)ROM_U16(&seq_gait_len[g]);
    }
    s.dir = dir;
    s.step = 0;
#if CFG_ENTRY_PATHS
    s.entry_left = 0;
#endif
    /* every step's state is below n_states: an unknown measured state matches none, and a
     * known one compares in cfg_state_t (no 32-bit compare per step) */
    for (i = 0; measured < n_states && i < s.n; i++) {
        if (step_state(i) == (cfg_state_t)measured) {
            s.step = i;
            break;
        }
    }
#if CFG_ENTRY_PATHS
    if (i == s.n && measured == 0u && dir != SEQ_DIR_LOADED) { /* from rest: the entry path */
        s.step = (step_ix_t)ROM_U16(&seq_entry_join[g]);
        s.entry_at = ROM_U16(&seq_entry_first[g]);
        s.entry_left = ROM_U16(&seq_entry_len[g]);
    }
#endif
    new_step();
    s.cycles = 0;
    s.running = 1;
    return SEQ_OK;
}

void seq_stop(void)
{
    s.running = 0;
}

uint8_t seq_tick(cfg_state_t measured)
{
    uint8_t ev = 0;
    if (!s.running) {
        return 0;
    }
    if (measured == target_state()) {
        if (!s.reached) {
            s.reached = 1;
            ev |= SEQ_EV_REACHED;
        }
        count_up(&s.held);
        if (s.held >= ticks.hold) {
#if CFG_ENTRY_PATHS
            if (s.entry_left) {
                s.entry_left--;
                s.entry_at++;
            } else
#endif
            if (++s.step >= s.n) {
                s.step = 0;
                count_up(&s.cycles);
                ev |= SEQ_EV_CYCLE;
            }
            new_step();
            return (uint8_t)(ev | SEQ_EV_ADVANCED);
        }
        return ev; /* a target held is never a timeout, however long hold_ms (SET_PARAM) */
    }
    s.held = 0;
#if SEQ_CLOCK_PAUSE
    if (!s.paused) /* a fall still coming down (seq.h) */
#endif
    count_up(&s.step_ticks); /* time away from the target: before it is reached, and after it is lost */
    if (s.step_ticks >= ticks.timeout) {
        s.running = 0;
        ev |= SEQ_EV_TIMEOUT;
    }
    return (uint8_t)(ev | SEQ_EV_AWAY);
}

uint8_t seq_running(void)
{
    return s.running;
}

uint8_t seq_holding(void)
{
    /* s.held: ticks at the target in a row, 0 once it is lost; not s.reached, which stays set
     * to the end of the step (SEQ_EV_REACHED once a step) */
    return (uint8_t)(s.running && s.held);
}

cfg_state_t seq_target(void)
{
    return s.n ? target_state() : 0u;
}

uint16_t seq_step(void)
{
    return ENTRY_LEFT ? SEQ_STEP_ENTRY : s.step;
}

/* One out-of-line copy of the clamp for the EVENT and the TELEMETRY frame (R1 on the Nano:
 * issue 11). Without an entry path and with one-byte steps there is no clamp (the step is
 * below 255): inline, a load where the call was (R1 on the Nano 2 B smaller). */
#if defined(__GNUC__) && (CFG_ENTRY_PATHS || !STEP_IX_BYTE)
__attribute__((noinline))
#endif
uint8_t seq_step_byte(void)
{
    uint16_t step = seq_step();
    return (uint8_t)(step > 255u ? 255u : step);
}

uint32_t seq_cycles(void)
{
    return s.cycles;
}

/* State numbers below CFG_N_STATES: 16-bit arithmetic when they fit (an 8-bit MCU then
 * carries no 32-bit multiply or compare here). */
#if CFG_N_STATES <= 65536UL
typedef uint16_t state_num_t;
#else
typedef uint32_t state_num_t;
#endif

/* The mixed-radix digits of `state`, most significant (limb 0) first, by subtracting
 * place values (a digit is below its limb's level count): no division in the tick. */
void seq_state_levels(cfg_state_t state, uint8_t levels[CFG_N_LIMBS])
{
#if PSI_UNIFORM_LEVELS && CFG_MAX_LEVELS == 2u && CFG_STATE_BYTES == 1 && CFG_N_LIMBS >= 2u
    /* Two levels per limb: the digits are the bits. Limb 0 takes every higher bit, as the
     * subtraction below does for a state past the last (8-bit states and at least two limbs:
     * its digit stays below 0xFF, so the subtraction's cap never applies). */
    uint8_t v = (uint8_t)state, i;
    for (i = CFG_N_LIMBS - 1u; i > 0u; i--) {
        levels[i] = (uint8_t)(v & 1u);
        v = (uint8_t)(v >> 1);
    }
    levels[0] = v;
#else
    state_num_t place[CFG_N_LIMBS];
    state_num_t v = (state_num_t)state;
    uint8_t i, d;
    place[CFG_N_LIMBS - 1] = 1u;
    for (i = CFG_N_LIMBS - 1u; i > 0u; i--) {
        place[i - 1u] = (state_num_t)(place[i] * psi_levels(i));
    }
    for (i = 0; i < CFG_N_LIMBS; i++) {
        for (d = 0; v >= place[i] && d < 0xFFu; d++) {
            v = (state_num_t)(v - place[i]);
        }
        levels[i] = d;
    }
#endif
}

cfg_state_t seq_state_index(const uint8_t levels[CFG_N_LIMBS])
{
    state_num_t v = 0;
    uint8_t i;
    for (i = 0; i < CFG_N_LIMBS; i++) {
        v = (state_num_t)(v * psi_levels(i) + levels[i]);
    }
    return (cfg_state_t)v;
}
