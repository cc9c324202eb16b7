/* angle.h - integer angles: sin and cos in Q14 of an angle in 0.01°, a Q14 turn, atan2.
 *
 * Contract. No floats, no division, no recursion; every function is exact or within the
 * stated error for every input in its range (checked exhaustively in tests/c/test_psi.c).
 * Angles are int16 in 0.01°; sin and cos are Q14 (16384 = 1). A {cos θ, sin θ} pair in Q14
 * describes a direction θ; a vector (x, z) stands for g·(sin ψ, cos ψ) as an accelerometer
 * reads gravity (ψ measured from +z towards +x), so angle_dot_q14 of a direction and a
 * sample is g·sin(ψ − θ)·2^14: its sign says ψ ≥ θ without an atan. The ψ classifier (psi.h)
 * and the level calibration's rotation (level.h) are built on these; angle_atan2_cdeg is the
 * one atan, for telemetry and what the controller asks of ψ itself.
 */
#ifndef PROLEG_ANGLE_H
#define PROLEG_ANGLE_H

#include <stdint.h>

/* sin and cos in Q14 of an angle in 0.01°, −9000..9000 (integer, error < 2 LSB). */
int16_t angle_sin_q14(int16_t cdeg);
int16_t angle_cos_q14(int16_t cdeg);

/* x·c − z·s for a Q14 {c, s} = {cos θ, sin θ}: 2^14·g·sin(ψ − θ) for the sample
 * (x, z) = g·(sin ψ, cos ψ). Exact (two 16×16→32 products). */
int32_t angle_dot_q14(int16_t c, int16_t s, int16_t x, int16_t z);

/* (x·c − z·s) / 2^14 for a Q14 {c, s} = {cos θ, sin θ}: the x of (x, z) turned by −θ (the
 * z is angle_turn_q14(c, −s, z, x)). Exact for |x·c − z·s| < 2^29: a vector shorter than 2^15
 * (every sample imucheck.c passes is within 1.5 g) turned by a Q14 unit {c, s}. */
int16_t angle_turn_q14(int16_t c, int16_t s, int16_t x, int16_t z);

/* atan2(x, z) in 0.01°, −18000..18000: the angle of (x, z) from +z towards +x (ψ of an
 * accelerometer sample (ax, az)); 0 for (0, 0). Error < 0.01°. */
int16_t angle_atan2_cdeg(int16_t x, int16_t z);

#endif /* PROLEG_ANGLE_H */
