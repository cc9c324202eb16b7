/* level.c - see level.h. */
#include "level.h"

#if CFG_LEVEL_CALIBRATION

#include <stddef.h>
#include <string.h>

#include "angle.h"
#include "crc16.h"
#include "fault.h"
#include "hal.h"
#include "initzero.h"
#include "imucheck.h"
#include "proto.h"
#include "psi.h"
#include "seq.h"
#include "tx.h"

#define PH_IDLE 0u
#define PH_SAMPLING 1u
#define PH_WRITING 2u
#define PH_CLEARING 3u

/* The record as stored: every target is little-endian (AVR, Cortex-M, the host), and the
 * layout has no padding (two bytes, then 16-bit fields). */
typedef struct {
    uint8_t magic;
    uint8_t limbs;
    int16_t off[CFG_N_LIMBS];
    uint16_t crc;
} level_rec_t;
typedef char level_rec_is_packed[sizeof(level_rec_t) == LEVEL_RECORD_BYTES ? 1 : -1];
typedef char level_rec_fits_nv[LEVEL_RECORD_BYTES <= HAL_NV_BYTES ? 1 : -1];

#define LEVEL_SAMPLES_LOG2 6
typedef char level_samples_is_2_to_the_log2[LEVEL_SAMPLES == (1 << LEVEL_SAMPLES_LOG2) ? 1 : -1];

static level_rec_t rec;  /* the record (hal_nv_write keeps a pointer to it while writing) */
static uint8_t status;   /* PROTO_LEVEL_NONE / STORED / CORRUPT */
static uint8_t phase;
static uint8_t left;     /* ticks of sampling left */
static uint8_t ground_mode; /* the calibration under way levels on this ground (RAM only) */
#if LEVEL_AT_REST
static uint16_t rest_ticks; /* ticks the robot has been at rest (up to LEVEL_REST_TICKS) */
/* A gait ran (or a fault latched) and the robot has not been at rest LEVEL_REST_TICKS since: no
 * calibration (level_calibrate). Kept across a reset that kept the coils' budget (level_init). */
static uint8_t after_gait NOINIT;
static uint8_t rest_limb;   /* the limb whose reading this tick low-passes */
#endif
static uint16_t waited;  /* ticks some limb had no sample yet */
static struct {
    int32_t sum;    /* ψ as corrected now, 0.01°, summed over the ticks */
    int16_t ground; /* this ground's tilt on top of the record, 0.01° */
    int16_t rc, rs; /* Q14 cos/sin of the whole tilt */
#if LEVEL_AT_REST
    int16_t rest;   /* ψ at rest as corrected now, low-passed over 2^LEVEL_REST_SHIFT of its samples */
#endif
} lm[CFG_N_LIMBS] NOINIT; /* per limb, in one record; kept across a reset for its ground (level_init) */

#if defined(__GNUC__)
__attribute__((noinline)) /* three callers: one copy */
#endif
static uint16_t rec_crc(void)
{
    return crc16_ccitt(CRC16_INIT, (const uint8_t *)&rec, offsetof(level_rec_t, crc));
}

#if defined(__GNUC__)
__attribute__((noinline)) /* four callers: one copy */
#endif
int16_t level_offset_cdeg(uint8_t limb)
{
    return status == PROTO_LEVEL_STORED ? rec.off[limb] : 0;
}

int16_t level_ground_cdeg(uint8_t limb)
{
    return lm[limb].ground;
}

#ifdef CFG_MAX_CLIMB_CDEG
#ifndef CFG_MAX_CLIMB_MX_CDEG
#define CFG_MAX_CLIMB_MX_CDEG CFG_MAX_CLIMB_CDEG /* one limit both ways */
#endif
static uint8_t tilted; /* this START, from rest, found an end beyond LEVEL_MAX_CDEG (level_at_start) */

#if defined(CFG_MAX_CLIMB_GAITS_PX) || defined(CFG_MAX_CLIMB_GAITS_MX)
#include "rom.h"
#ifdef CFG_MAX_CLIMB_GAITS_PX
static const uint16_t climb_px[] ROM = {CFG_MAX_CLIMB_GAITS_PX};
#endif
#ifdef CFG_MAX_CLIMB_GAITS_MX
static const uint16_t climb_mx[] ROM = {CFG_MAX_CLIMB_GAITS_MX};
#endif

/* A built-in gait's own limit where the robot file lists one per gait; else its way's. */
static uint16_t climb_limit(uint8_t minus_x, uint8_t gait)
{
#ifdef CFG_MAX_CLIMB_GAITS_PX
    if (!minus_x && gait < sizeof climb_px / sizeof climb_px[0]) {
        return ROM_U16(&climb_px[gait]);
    }
#endif
#ifdef CFG_MAX_CLIMB_GAITS_MX
    if (minus_x && gait < sizeof climb_mx / sizeof climb_mx[0]) {
        return ROM_U16(&climb_mx[gait]);
    }
#endif
    return minus_x ? CFG_MAX_CLIMB_MX_CDEG : CFG_MAX_CLIMB_CDEG;
}
#else
#define climb_limit(minus_x, gait) ((void)(gait), (minus_x) ? CFG_MAX_CLIMB_MX_CDEG : CFG_MAX_CLIMB_CDEG)
#endif

uint16_t level_too_steep(uint8_t minus_x, uint8_t gait)
{
    /* twice the rise; |ground| ≤ LEVEL_MAX_CDEG each: fits */
    int16_t rise2 = (int16_t)(lm[0].ground - lm[CFG_N_LIMBS - 1u].ground);
    if (tilted) {
        return LEVEL_TOO_TILTED; /* a ground no calibration takes: uphill or down, not one to walk */
    }
    if (minus_x) {
        rise2 = (int16_t)-rise2;
    }
    return status == PROTO_LEVEL_STORED && rise2 > 2 * (int16_t)climb_limit(minus_x, gait)
               ? (uint16_t)rise2 >> 1
               : 0u;
}
#define SET_TILTED(v) (tilted = (v))
#else
#define SET_TILTED(v) ((void)0)
#endif

/* Read the record back: its status, then each limb's rotation (the record's only if valid).
 * The tilts tracked at rest were against the old rotation: tracking starts over. */
static void load(void)
{
    uint8_t i;
    int16_t a;
#if LEVEL_AT_REST
    rest_ticks = 0;
#endif
    hal_nv_read((uint8_t *)&rec, LEVEL_RECORD_BYTES);
    status = rec.magic == 0xFFu ? PROTO_LEVEL_NONE
             : (rec.magic == LEVEL_MAGIC && rec.limbs == CFG_N_LIMBS && rec.crc == rec_crc()) ? PROTO_LEVEL_STORED
                                                                                             : PROTO_LEVEL_CORRUPT;
    for (i = 0; i < CFG_N_LIMBS; i++) {
        a = (int16_t)(level_offset_cdeg(i) + lm[i].ground);
        lm[i].rc = angle_cos_q14(a);
        lm[i].rs = angle_sin_q14(a);
    }
}

static void set_ground(const int16_t *o);

void level_init(uint8_t kept)
{
    phase = PH_IDLE;
    /* A power-on (or RAM this build did not leave): no ground levelled on, and at rest as far
     * as anything was driven. A reset that kept the coils' budget (a Nano's port opened, a
     * brown-out) keeps both. It forgot them: a START at once after a reconnect found no slope
     * (the ground levelled on at rest needs 2 s at rest to come back), and R1 on the Nano
     * started up a 6° slope its 2.5° climb guard had just refused; a calibration 1 s after a
     * reset that came 0.1 s after STOP stored R1's still-falling ends (9.7° and 4.3°) as
     * mounting tilts. The rest of lm[] is set again before it is read. */
    if (!kept) {
#if LEVEL_AT_REST
        after_gait = 0;
#endif
        set_ground(0);
    }
    load();
}

void level_apply(uint8_t limb, int16_t *ax, int16_t *az)
{
    int16_t x = *ax, z = *az, c = lm[limb].rc, s = lm[limb].rs;
    if (s != 0) { /* a tilt of 0.01° already has sin ≥ 2 in Q14; 16×16→32 products */
        *ax = angle_turn_q14(c, s, x, z);            /* x·c − z·s */
        *az = angle_turn_q14(c, (int16_t)-s, z, x); /* z·c + x·s */
    }
}

int8_t level_calibrate(uint8_t on_this_ground)
{
    uint8_t i;
    if (phase != PH_IDLE) {
        return -1;
    }
#if LEVEL_AT_REST
    if (after_gait) {
        return -3; /* its limbs may still come down, its coils still cool (level.h) */
    }
#endif
    for (i = 0; i < CFG_N_LIMBS; i++) {
        lm[i].sum = 0;
    }
    ground_mode = on_this_ground;
    left = LEVEL_SAMPLES;
    waited = 0;
    phase = PH_SAMPLING;
    return 0;
}

/* A tilt no calibration takes: beyond LEVEL_MAX_CDEG either way (flat or this ground). */
static uint8_t too_tilted(int16_t o)
{
    return o > LEVEL_MAX_CDEG || o < -LEVEL_MAX_CDEG;
}

/* This ground's tilt per limb: `o`, or 0 with o = 0. */
static void set_ground(const int16_t *o)
{
    uint8_t i;
    for (i = 0; i < CFG_N_LIMBS; i++) {
        lm[i].ground = o ? o[i] : 0;
    }
}

#if defined(__GNUC__)
__attribute__((noinline)) /* two callers: one copy */
#endif
static void write(uint8_t n, uint8_t ph)
{
    phase = hal_nv_write((const uint8_t *)&rec, n) == 0 ? ph : PH_IDLE;
}

int8_t level_clear(void)
{
    if (phase != PH_IDLE) {
        return -1;
    }
    rec.magic = 0xFFu; /* the erased magic: no record */
    status = PROTO_LEVEL_NONE;
    set_ground(0);
    write(1, PH_CLEARING);
    return 0;
}

/* The end of a calibration: what holds now (the old record unless the new one was written
 * and reads back valid), and the EVENT. */
static void done(uint8_t result, uint16_t detail)
{
    phase = PH_IDLE;
    load();
    if (result == PROTO_LEVEL_RES_STORED && status != PROTO_LEVEL_STORED && !ground_mode) {
        result = PROTO_LEVEL_RES_WRITE_FAILED;
    }
    tx_event(PROTO_EV_LEVEL_DONE, result, detail);
}

/* Sampling is over: each limb's tilt (the one in use plus the mean), checked, then applied
 * (this ground) or stored (flat). */
static void measured(void)
{
    uint8_t i, far = 0;
    int16_t o[CFG_N_LIMBS];
    for (i = 0; i < CFG_N_LIMBS; i++) {
        /* sum / LEVEL_SAMPLES (C rounds towards 0) as a shift: the signed division would link
         * libgcc's __divmodsi4. An arithmetic shift (gcc and clang) rounds down, so a negative sum
         * is first raised by LEVEL_SAMPLES - 1: the shift then rounds it up, towards 0, as the
         * negated shift of its magnitude did (R1 26 B smaller on the Nano). |sum| ≤ 64 × 18000 < 2^21:
         * no overflow, and the quotient fits an int16. */
        int32_t sum = lm[i].sum;
        if (sum < 0) {
            sum += LEVEL_SAMPLES - 1;
        }
        o[i] = (int16_t)(lm[i].ground + (int16_t)(sum >> LEVEL_SAMPLES_LOG2));
        if (!ground_mode) {
            o[i] = (int16_t)(o[i] + level_offset_cdeg(i));
        }
        if (too_tilted(o[i])) {
            far |= (uint8_t)(1u << i);
        }
    }
    if (far) {
        done(PROTO_LEVEL_RES_TOO_TILTED, far);
        return;
    }
    if (ground_mode) {
        set_ground(o);
        done(PROTO_LEVEL_RES_STORED, 0); /* applied (this ground only: not stored) */
        return;
    }
    set_ground(0);
    memcpy(rec.off, o, sizeof o);
    rec.magic = LEVEL_MAGIC;
    rec.limbs = CFG_N_LIMBS;
    rec.crc = rec_crc();
    write(LEVEL_RECORD_BYTES, PH_WRITING);
    if (phase != PH_WRITING) {
        done(PROTO_LEVEL_RES_WRITE_FAILED, 0);
    }
}

#if LEVEL_AT_REST
/* Between gaits: how long has the robot been at rest, and what does each limb read there?
 * At rest = no gait, no fault, every limb at level 0; the limbs' readings are then
 * low-passed in turn, one limb a tick (first order over 2^LEVEL_REST_SHIFT of its samples;
 * at 1.5° of IMU noise the estimate's σ is 0.13°). Anything else starts over. */
static void track_rest(void)
{
    uint8_t i, shift;
    int16_t a;
    if (seq_running() || fault_latched()) {
        after_gait = 1;
        goto moving; /* (before any ψ is computed: a gait's ticks pay nothing for this) */
    }
    for (i = 0; i < CFG_N_LIMBS; i++) {
        if (psi_level(i) != 0u) { /* raised, or no sample yet (PSI_UNKNOWN) */
            goto moving;
        }
    }
    i = rest_limb;
    a = psi_last_centideg(i); /* one atan2 a tick, not one per limb: an idle tick stays short */
    /* >> of a negative int16: an arithmetic shift on every compiler proleg uses. Each limb's
     * first sample is taken as it is: a shift of 0 (rest + (a − rest) is a, also where the
     * int16 difference wraps: the sum wraps back). One expression, not two: avr-gcc computed
     * lm[i]'s address twice for the two (R1 20 B smaller on the Nano). */
    shift = rest_ticks >= CFG_N_LIMBS ? LEVEL_REST_SHIFT : 0u;
    lm[i].rest = (int16_t)(lm[i].rest + ((int16_t)(a - lm[i].rest) >> shift));
    rest_limb = (uint8_t)(i + 1u < CFG_N_LIMBS ? i + 1u : 0u);
    if (rest_ticks < LEVEL_REST_TICKS) {
        rest_ticks++;
    } else {
        after_gait = 0;
    }
    return;
moving:
    rest_ticks = 0;
    rest_limb = 0;
}

void level_at_start(void)
{
    uint8_t i;
    int16_t o;
    SET_TILTED(0);
    if (rest_ticks < LEVEL_REST_TICKS || status != PROTO_LEVEL_STORED) {
        return; /* not known to be at rest, or no flat record to measure the ground against */
    }
    for (i = 0; i < CFG_N_LIMBS; i++) {
        o = (int16_t)(lm[i].ground + lm[i].rest); /* |ground| ≤ 2000, |rest| ≤ 18000: no overflow */
        if (too_tilted(o)) {
            SET_TILTED(1); /* the climb guard refuses it */
            return; /* not a ground to level on (level_calibrate(1) refuses it too): keep the one in use */
        }
    }
    for (i = 0; i < CFG_N_LIMBS; i++) {
        lm[i].ground = (int16_t)(lm[i].ground + lm[i].rest);
    }
    load();
}
#endif

void level_poll(void)
{
    uint8_t i, dead = imucheck_bad();
    int8_t r;
    if (phase == PH_SAMPLING) {
        for (i = 0; i < CFG_N_LIMBS; i++) {
            if (psi_level(i) == PSI_UNKNOWN) {
                dead |= (uint8_t)(1u << i); /* starting up: wait for it, a while */
            }
        }
        if (imucheck_bad() || (dead && ++waited > LEVEL_WAIT_TICKS)) {
            done(PROTO_LEVEL_RES_IMU, dead);
        } else if (seq_running() || fault_latched()) {
            done(PROTO_LEVEL_RES_INTERRUPTED, 0);
        } else if (!dead) {
            for (i = 0; i < CFG_N_LIMBS; i++) {
                lm[i].sum += psi_last_centideg(i);
            }
            if (--left == 0u) {
                measured();
            }
        }
    } else if (phase == PH_IDLE) {
#if LEVEL_AT_REST
        track_rest();
#endif
    } else {
        r = hal_nv_poll();
        if (r == HAL_NV_BUSY) {
            return;
        }
        if (phase == PH_CLEARING) {
            phase = PH_IDLE;
            load();
        } else {
            done(r == 0 ? PROTO_LEVEL_RES_STORED : PROTO_LEVEL_RES_WRITE_FAILED, 0);
        }
    }
}

uint8_t level_status(void)
{
    return (phase == PH_SAMPLING || phase == PH_WRITING) ? PROTO_LEVEL_CALIBRATING : status;
}
#else
typedef char level_left_out; /* CFG_LEVEL_CALIBRATION = 0 (ISO C wants a declaration) */
#endif
