/* angle.c - see angle.h. */
#include "angle.h"

#include "rom.h"

#if defined(__GNUC__)
#define NOINLINE __attribute__((noinline)) /* many callers: one copy on the 8-bit targets */
#else
#define NOINLINE
#endif

/* sin(min(i · 1.28°, 90°)) in Q14, i = 0..71: a power-of-two step of 128 × 0.01°, so the
 * lookup is a shift and a mask (no 32-bit division). Linear interpolation between entries
 * is within 2 LSB of sin everywhere (checked for every 0.01° in tests/c/test_psi.c). */
static const int16_t sin_tab[72] ROM = {
    0,     366,   732,   1097,  1462,  1826,  2190,  2552,  2913,  3272,  3630,  3986,
    4340,  4692,  5041,  5388,  5732,  6074,  6412,  6747,  7079,  7408,  7732,  8053,
    8370,  8682,  8990,  9294,  9593,  9888,  10177, 10461, 10740, 11014, 11282, 11545,
    11802, 12052, 12297, 12536, 12769, 12995, 13214, 13428, 13634, 13833, 14026, 14212,
    14390, 14562, 14726, 14883, 15032, 15174, 15308, 15435, 15554, 15665, 15768, 15864,
    15951, 16031, 16102, 16166, 16221, 16269, 16308, 16339, 16362, 16377, 16384, 16384,
};

/* atan((i+1)/32) − atan(i/32) in 0.01°, i = 0..31: atan(i/32) is the sum of the first i
 * (0, 179, 358, 536, … 4409, 4500). Steps below 256: half the bytes of the sums (issue 11). */
static const uint8_t atan_step[32] ROM = {
    179, 179, 178, 177, 175, 174, 172, 170, 167, 164, 162, 159, 155, 152, 148, 146,
    141, 138, 134, 131, 126, 124, 120, 116, 113, 109, 107, 103, 99,  97,  94,  91,
};

/* |v| as uint16 (|−32768| = 32768). One out-of-line copy for sin, cos and atan2. */
static NOINLINE uint16_t mag(int16_t v)
{
    return v < 0 ? (uint16_t)(0u - (uint16_t)v) : (uint16_t)v;
}

int16_t angle_sin_q14(int16_t cdeg)
{
    uint16_t i, f, a;
    int16_t v;
    uint16_t x = mag(cdeg);
    if (x >= 9000u) {
        v = 16384;
    } else {
        i = x >> 7;   /* ≤ 70 */
        f = x & 127u;
        a = (uint16_t)ROM_I16(&sin_tab[i]);
        /* the table rises by at most 366 per entry: 366 × 127 + 64 fits in 16 bits */
        v = (int16_t)(a + ((((uint16_t)ROM_I16(&sin_tab[i + 1u]) - a) * f + 64u) >> 7));
    }
    return cdeg < 0 ? (int16_t)-v : v;
}

#if defined(__GNUC__)
__attribute__((noinline)) /* six callers: one copy */
#endif
int16_t angle_cos_q14(int16_t cdeg)
{
    return angle_sin_q14((int16_t)(9000 - mag(cdeg))); /* sin(90° − |cdeg|) */
}

/* Called from many places (psi.c); kept out of line so that the 8-bit targets carry the two
 * 32-bit products once. */
#if defined(__GNUC__)
__attribute__((noinline))
#endif
int32_t angle_dot_q14(int16_t c, int16_t s, int16_t x, int16_t z)
{
    return (int32_t)x * c - (int32_t)z * s;
}

/* p / 2^14 as int16 (bits 14..29): a 2-bit shift and a byte move, where an 8-bit MCU would
 * shift 32 bits 14 times. Exact for |p| < 2^29. */
#define Q14_TO_I16(p) ((int16_t)(uint16_t)(((uint32_t)(p) << 2) >> 16))

NOINLINE int16_t angle_turn_q14(int16_t c, int16_t s, int16_t x, int16_t z)
{
    return Q14_TO_I16(angle_dot_q14(c, s, x, z));
}

/* atan(n/d) in 0.01° for 0 ≤ n ≤ d, d > 0: table plus linear interpolation. */
static int16_t atan_frac(uint16_t n, uint16_t d)
{
    uint16_t r = 0, rem = n; /* r = n·2^15 / d (Q15, 0..32768) by shift and subtract: */
    uint8_t k;               /* no 32-bit division (issue 11) */
    if (n >= d) {
        r = 32768u;
    } else {
        for (k = 0; k < 15u; k++) {
            rem = (uint16_t)(rem << 1); /* rem < d ≤ 32768: 2·rem < 2^16 */
            r = (uint16_t)(r << 1);
            if (rem >= d) {
                rem = (uint16_t)(rem - d);
                r |= 1u;
            }
        }
    }
    uint8_t i = (uint8_t)(r >> 10); /* 0..32 */
    uint16_t f = (uint16_t)(r & 1023u);
    uint8_t step = 0;
    int16_t a = 0;
    for (k = 0; k < i; k++) {
        a = (int16_t)(a + ROM_U8(&atan_step[k])); /* atan(i/32) */
    }
    if (i < 32u) {
        step = ROM_U8(&atan_step[i]); /* to atan((i+1)/32); r = 32768 (i = 32) has f = 0 */
    }
    /* step ≤ 179: unsigned 16×16→32 */
    return (int16_t)(a + (int16_t)(((uint32_t)step * f + 512u) >> 10));
}

int16_t angle_atan2_cdeg(int16_t x, int16_t z)
{
    uint16_t ux = mag(x); /* |−32768| = 32768 */
    uint16_t uz = mag(z);
    int16_t a;
    if (ux == 0u && uz == 0u) {
        return 0;
    }
    a = (ux <= uz) ? atan_frac(ux, uz) : (int16_t)(9000 - atan_frac(uz, ux));
    if (z < 0) {
        a = (int16_t)(18000 - a);
    }
    return x < 0 ? (int16_t)-a : a;
}
