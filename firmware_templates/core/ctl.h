/* ctl.h - from (measured levels, target levels) to a duty per actuator.
 *
 * Contract, per limb, in order:
 * - rising (target above its level) → the drive duty: heat, ψ rises. A limb that heats
 *   CTL_BOOST_MS without getting one progress edge closer (psi_to_go_cdeg) lags (weak
 *   supply, draught, cold start, worn coil): from then on until ctl_reset (START) its rises
 *   and hold re-heats use the build's duty ceiling CFG_MAX_DUTY_PM (sma.c clamps and counts
 *   it like any other duty);
 * - falling (target below) → off: the body's elasticity lowers ψ;
 * - holding a level L ≥ 1: closed loop on ψ, bang-bang with hysteresis. Below the hold
 *   edge of threshold L−1 (its upper band edge plus CFG_HOLD_MARGIN_CDEG) the coil heats
 *   at the drive duty until ψ reaches the hold top (the hold edge plus
 *   PSI_HOLD_BAND_CDEG), then it is off until ψ sags below the hold edge again;
 * - holding any level not yet settled (psi.h: clear of its margins, with hysteresis and
 *   dwell) → off: it must first get clear of the threshold above;
 * - holding level 0 → off.
 *
 * Why bang-bang on ψ and not a fixed hold duty: an SMA coil that cools below its
 * martensite start Ms relaxes, and heating it again contracts it only once it is back
 * above its austenite start As (transformation hysteresis). Which duty keeps a coil
 * between the two depends on the supply, the air, the ambient, the coil's age: a fixed
 * duty overheats or lets it drop on most robots. ψ itself says when the coil has relaxed
 * enough to matter; the hold margin leaves room for the re-heat (the coil warms from Ms
 * back to As within tens of ms at the drive duty), and the band above it keeps the
 * switching rate low. Every off phase also lets the on-time limit (sma.c) restart.
 *
 * Steps that change several limbs at once (the friction states must change together,
 * or the robot makes two transitions with other rewards). Distances to a crossing come
 * from psi_to_go_cdeg() (comparisons against Q14 edges, no atan; 1° resolution within
 * 6°, coarser beyond):
 * - all rising: a limb more than CTL_SYNC_CDEG ahead of the farthest waits at the hold duty,
 *   so that they cross together even when their coils start at different temperatures;
 * - some falling: a rising limb climbs to within CTL_SYNC_ZONE_CDEG of its crossing and
 *   waits there until every falling limb is within CTL_SYNC_CDEG of its own; a falling limb
 *   is never held back for this (that would mean re-heating its coil).
 * - While any held raised limb sags below its hold edge, falling limbs wait at the hold
 *   duty: through the body they may be what holds it up (a step like 11 → 01 on coupled
 *   coils), and a coil kept warm stops relaxing until the sagging limb's coil caught it.
 *   At most CTL_SAG_WAIT_MS per limb and step: with several limbs held, one of them is
 *   nearly always in a hold pulse, and a falling coil kept warm for good never crosses.
 *   Only a neighbour (limb i−1 or i+1) counts; with three or more limbs only one that sagged
 *   to within CTL_SYNC_CDEG of its band's lower edge (about to drop a level): on a long body
 *   every step tilts the held limbs by a few degrees through the body, and a falling coil
 *   kept warm for such a sag only waited (docs/control.md, "Long bodies").
 *
 * Full strokes (robot file [[limb]] stroke_deg, built in only when a limb has one): such a
 * limb is held at its stroke on its top level (psi.h: the hold edge of its top threshold),
 * not just past ψ*, so the step reaches that level only once the limb got there. Driven this
 * far a coil bends the whole body, and which end leads decides which end slides while it
 * bends (docs/control.md, "Full strokes"); an end that started to slide keeps sliding
 * (kinetic friction is below static). So limbs rising to their strokes together:
 * - all rising: instead of crossing together, the rise lead (CFG_STROKE_RISE_LEAD: robot
 *   file control.stroke_rise_lead, by default the largest stroke) crosses first; the others
 *   wait until it has: at the hold duty (warming their coils) for at most CTL_SAG_WAIT_MS,
 *   then off (a coil that cannot heat must not keep another one on);
 * - then they climb in step: a limb that has covered more than CTL_SHARE_SYNC /
 *   CTL_SHARE_FULL (5 %) more of its climb (from its top band's upper edge to its stroke)
 *   than another waits at the hold duty (not hovering meanwhile), until CTL_CLIMB_MAX_MS
 *   after the step began, and only while the lagging limb still rises (CTL_LAG_MS): a limb
 *   that cannot rise must not hold the others down; a limb not across its band yet has
 *   covered none. Only limbs the step raises climb in step: one
 *   already at its stroke when the step began is held as usual. A limb that stopped short of
 *   its stroke in this robot step (below: a worn coil, a weak supply) sets how far the others
 *   climb: one more than CTL_SHARE_SYNC past its share that has gained nothing for
 *   CTL_CLIMB_STOP_MS / 2 waits at the hold duty and counts as stopped there (one still
 *   gaining climbs on: at a weak supply the two coils together bend the body further than
 *   either alone, and a cap on the first that stopped held R1 at 36° of 76°). Fatigue takes stroke off every coil alike: R1's ends both topped out at 66° and,
 *   the right one climbing on to it, lost the order of their strokes that makes the ratchet
 *   (the right end, raised less, comes down first): 0.34 mm/s against 6.85 fresh.
 * Falling from their strokes together (no limb rising), they fall as their coils cool: the
 * one bent least comes down first. With a fall lead (CFG_STROKE_FALL_LEAD: robot file
 * control.stroke_fall_lead, built in only when given) the others are held at their strokes
 * (or where they stopped short: bang-bang at the drive duty) until the fall lead is halfway
 * down its climb (CTL_FALL_SHARE / CTL_SHARE_FULL), for at most CTL_FALL_WAIT_MS: on R2's
 * pads the same end must lead up and down.
 * hold_pm is only used for these waits.
 *
 * Stall detector, per limb and step (a step = an unchanged target level):
 * - oscillating at the threshold: the level changed CTL_OSC_CROSSINGS times in this step,
 *   or the limb sat at its target level without settling for CTL_HOVER_MS. Recovery: the
 *   limb settles on the band edges alone (psi_relax), so the sequencer can go on, and
 *   the bang-bang hold keeps it above ψ*. A limb climbing to its stroke (below) is not
 *   hovering while it still climbs: its clock restarts whenever its smoothed ψ gained
 *   CTL_CLIMB_GAIN_CDEG, so it is relaxed (and the step goes on) once it stops climbing short
 *   of the stroke (CTL_CLIMB_STOP_MS without a gain; a hover time while another limb in step
 *   waits for it, its coil's help withdrawn), or CTL_CLIMB_MAX_MS after the step
 *   began. Relaxed by the crossings instead (IMU noise at its band) it is heated on while it
 *   still gains CTL_CLIMB_GAIN_CDEG a hover time;
 *   once it has stopped, in that step and the robot's later steps that leave it raised, it
 *   is held where it stopped (1° band, its edge 1° below
 *   where it stopped but not below the hold edge it has without a stroke) - a weak supply or
 *   a worn coil still walks, with less stroke;
 * - cannot reach the state: rising and heating at the drive duty without getting one
 *   progress edge closer (psi_to_go_cdeg) for CTL_STALL_MS. The coil is switched off (cold coils when the
 *   sequencer's state timeout reports the fault).
 * ctl_stall() tells which; both clear when the limb's target changes.
 *
 * An actuator that drives several limbs serves the strongest demand of its limbs: boost
 * over heat over release over hold. Levels come from psi.h. Why and where the time goes:
 * docs/control.md. ctl.c turns levels and targets into duties; the watches on each limb's
 * step (the stall detector, the reach, hold, lag and fall watches) are stall.c's (stall.h).
 */
#ifndef PROLEG_CTL_H
#define PROLEG_CTL_H

#include <stdint.h>

#include "robot_config.h"
#include "seq.h" /* SEQ_CLOCK_PAUSE */

/* Synchronised steps (see above), in 0.01°. */
#define CTL_SYNC_CDEG 200
#define CTL_SYNC_ZONE_CDEG 600

/* Stall detector (see above). */
#define CTL_OSC_CROSSINGS 3u
#define CTL_HOVER_MS 300u
/* A limb climbing to its stroke has stopped once its smoothed ψ gained less than
 * CTL_CLIMB_GAIN_CDEG in CTL_CLIMB_STOP_MS: the rate of CTL_CLIMB_CDEG in a hover time
 * (3.3°/s), seen in half the time. At the end of its travel the coil heats on at ≈ 60 °C/s
 * (drive duty 0.8), and a worn coil (its transformation shifted up) ends its travel near
 * 105 °C: told after 1° in 300 ms, R1's worn coils at full strokes reached 119-121 °C (NiTi is
 * ruined past ≈ 120 °C: sim/physical/materials.py). A finer gain is safe under IMU noise
 * because it is the smoothed ψ. */
#define CTL_CLIMB_STOP_MS 150u
#define CTL_CLIMB_GAIN_CDEG 50
#define CTL_CLIMB_CDEG 100
/* Limbs climbing to their strokes together (see above): shares of the climb, 0..FULL. */
#define CTL_SHARE_FULL 256
#define CTL_SHARE_SYNC 13
#define CTL_FALL_WAIT_MS 2000u
#ifndef CTL_FALL_SHARE
#define CTL_FALL_SHARE 128
#endif
#define CTL_CLIMB_MAX_MS 3000u
/* Lag watch: limbs climbing in step wait for a lagging limb below its band only while it still
 * rises: once it has heated at the drive duty this long without getting one progress edge
 * closer to its crossing (the stall detector's clock: 1° near it, 2-5° farther), the others go
 * on, for the rest of the step (what it gains then, their climb gives it). A limb on its top
 * level needs no such watch: one that stops climbing there is relaxed a hover time later and no
 * longer climbs in step. R1 at full strokes with a dead right coil: the left end
 * waited warm for the right one's climb until CTL_CLIMB_MAX_MS at every rise, the dead coil on
 * meanwhile, and its on-time limit cut it in every cycle (docs/control.md, "Full strokes").
 * 1 s covers a healthy coil's dead time from the hold duty back to As (0.15-0.6 s) with room,
 * and a transforming coil gains tens of degrees a second; the dead end, lifted through the body
 * by the other end's warm coil, crept up to ≈ 1°/s, an edge every 1.5-2.5 s. Kept in the stall
 * detector's clock, it costs the Nano's tick nothing measurable; a watch of its own on the
 * smoothed ψ (an atan2 every 16 ticks) took R1 at full strokes from busy p99 688 µs / max 845
 * to 713-745 / 993-1026 µs, past the tick budget (bench/bench_mcu.py). */
#define CTL_LAG_MS 1000u
/* Knee watch: a limb the step raises to its stroke, its coil heated at the drive duty, whose
 * smoothed ψ gained less than 1/2^CTL_KNEE_SHIFT of the most it gained in one CTL_KNEE_MS
 * window of the same heat (at least CTL_KNEE_FAST_CDEG) has a coil through its
 * transformation: more heat only heats the wire, ≈ 60 K/s at 0.8 duty on R1 (its ψ answers
 * the other coils, if anything). It is "spent" for the rest of the step: heated at most at the
 * hold duty; on its top level it counts as stopped short of its stroke (held where it
 * stopped), below its band it no longer leads nor is waited for (the others' climb lifts it
 * through the body). Judged against the coil's own transformation, not a fixed rate:
 * - a transforming coil at a nominal supply bends its end 100-160°/s (R1 at full strokes), and
 *   a coil at its end creeps at the rate the others' coils give it: R1's left end with ψ*
 *   moved to 70° crept 3°/s at 0.8 duty, its coil 85 -> 166 °C (docs/safety.md); a worn coil
 *   stopped dead 0.5 s before the hover clock told it (125 °C; docs/plant.md, "Off the grid");
 * - 4° in 80 ms (50°/s) arms it only on a coil seen transforming fast in this heat: a weak
 *   supply's slow climb, which reaches no dangerous temperature, is left to the hover clock
 *   as before; under IMU noise (1.5° RMS, a fifth of it smoothed) an 80 ms gain is ±0.4°;
 * - a coil held at the hold duty or off meanwhile starts over: heated again from below As
 *   it gains nothing for its dead time (0.15-0.6 s), which is no knee.
 * Hold-watch builds (CFG_HOLD_WATCH, no strokes) carry it for the coil (stall.h KNEE_COIL):
 * every limb on a coil asked for the drive duty is watched, whichever limb asks, and the coil,
 * once spent, gets at most the hold duty until the robot's next step (or until that limb drops
 * a level: its coil has cooled back through its transformation). The same constants fit: the
 * one-actuator R1's coil bends its own end 60-80°/s at 0.8 duty (5-6° a window) and stops dead
 * past Af, while the far end it lifts through the body moves ≈ 30°/s (2.4° a window, never
 * armed by itself) and crept on by tenths: heated for it, the coil reached 136 °C (worn by
 * 14,758 cycles; docs/plant.md, "Off the grid"). At 0.6 duty inchworm-3's coils bend their ends
 * 36-44°/s, under the 50°/s that arms it: there (and on caterpillar-4) it rarely arms, and the
 * reach and hold watches bound their heats as before. */
#define CTL_KNEE_MS 80u
#define CTL_KNEE_FAST_CDEG 400
#define CTL_KNEE_SHIFT 3
#define CTL_STALL_MS 5000u
/* A rise that ψ no longer answers. A limb rising alone (the body couples limbs that move
 * together), its coil heating and not held off by the envelope, whose smoothed ψ
 * (psi_smooth_cdeg, looked at every CTL_REACH_EVERY ticks) rose CTL_MOVE_CDEG from its lowest
 * in this step and then gained less than CTL_GAIN_CDEG for CTL_REACH_MS cannot get there: its
 * coil is through its transformation (or at its supply's equilibrium) short of the level, and
 * more heat only heats the wire. It stops as "cannot reach" at once instead of after
 * CTL_STALL_MS without progress (which IMU noise keeps from running out) or at its on-time
 * limit: the one-actuator R1 after 30,000 cycles' stroke loss heated its coil to 169 °C within
 * the envelope, now 112 °C (docs/control.md). 0.4° in 320 ms is a rise of 1.25°/s, far below a
 * transforming coil's tens of degrees a second and below the creep of a coil at a weak
 * supply's equilibrium that still gets there; past Af R1's coil heats ≈ 11 K per 100 ms at 0.8
 * duty. The 4° rise from the lowest keeps IMU noise (smoothed, up to 3° RMS) while a cool coil
 * heats back to As (its dead time, 0.15-0.6 s) from counting as a rise. */
#define CTL_MOVE_CDEG 400
/* The hold watch (CFG_HOLD_WATCH, builds with the reach watch): a held limb that the stall
 * detector relaxed (it never settled clear of its hold edge), that is settled clear of its band
 * (the step needs nothing more of it) and heats below its hold edge is watched the same way,
 * without the 4° rise: once its smoothed ψ gained less than CTL_GAIN_CDEG for CTL_REACH_MS it is
 * held where it stopped, its coil off until its smoothed ψ sags CTL_CLIMB_CDEG below its
 * highest, then re-heated and watched afresh; a limb that drops out of its level meanwhile rises
 * back on a fresh reach watch. A worn coil (stroke lost)
 * whose reach fell to just past the limb's top level can no longer reach its hold edge; the
 * bang-bang hold heated it on below that edge, through the rest of the robot's steps:
 * caterpillar-4's rear proleg at 30,000 cycles' fatigue reached 135 °C at ψ 25.4°, its hold
 * edge 27°. The renderer builds it in where the robot's body (its [plant] table) leaves a limb's
 * hold top within a worn coil's stroke loss of its reach (proleg.robot_body.worn_holds); where
 * it does not (R1: ψ* 20°, reach 80°) it costs no flash. */
#ifndef CFG_HOLD_WATCH
#define CFG_HOLD_WATCH 0
#endif
#define CTL_GAIN_CDEG 40
#define CTL_REACH_MS 320u
#define CTL_REACH_EVERY 16u
/* Rising without progress for this long: heat at the duty ceiling (0: off). The robot file's
 * control.boost_ms (robot_config.h): by default 700 ms where the body's reach says a lag can
 * only be a coil short of heat, none where a worn coil may end short of a hold or the drive
 * duty is already the ceiling (proleg.robot_reach.boost_ms_of). It gives heating-limited
 * conditions (weak supply, draught, a cold start) back their rises (docs/control.md, "The
 * boost"). */
#ifndef CTL_BOOST_MS
#define CTL_BOOST_MS 0u
#endif
/* Longest wait of a falling limb per step: a held coil whose ψ sags has cooled through its
 * transformation and needs ≈ 0.3-0.4 s at the drive duty to re-heat to As (≈ 45 → 64 °C at
 * ≈ 60 K/s on R1); released earlier, the falling end drags it below ψ* (11 → 00 → 10 on the
 * table plant instead of 11 → 10). */
#define CTL_SAG_WAIT_MS 500u
/* Held up: on a body of three or more limbs, a limb whose neighbours hold it up into the band
 * above its target level (caterpillar-4's front proleg at 12-12.6° in 0101, its band 11..13°,
 * the rear proleg held at 19° and the head at 27°) reads its level (hysteresis) but never
 * settles clear of that band, even relaxed to the band edges, and its coil is already off:
 * the step ended in STATE_TIMEOUT "every limb at its level, one would not settle" (proleg
 * learn --plant physical stopped there on every seed). Relaxed and still unsettled a further
 * CTL_HOVER_MS, it settles on the band edge below alone (psi.h PSI_RELAX_HELD_UP). Not built
 * for two limbs: there the other end is lifted past its band or not into it (R1: 23.5° at full
 * stroke, ≈ 8-10° at the hold), and R1's image has no bytes to spare (14 KB target). */
#define CTL_HELD_UP PSI_HELD_UP
/* Held up on the way down (the same builds): a falling limb, its coil off, whose neighbours'
 * holds keep it in the band above its target level. caterpillar-4 in 1110 -> 1010, learned on
 * the physical plant: the rear proleg's coil cold at 25 °C, the rear at 11.7-12.4° against
 * its band's lower edge 11°, held there by the tail's hold (24.6-27°, its band 19..21°) and
 * the front's (16.6-19°, band 11..13° below it) until STATE_TIMEOUT. Once a falling limb
 * within 2° of its crossing (farther, its coil may still be cooling to Ms: in a hot enclosure
 * for seconds, and holding the others low then only shortened their steps) has not had its
 * smoothed ψ (looked at every CTL_REACH_EVERY ticks) drop CTL_CLIMB_CDEG below its lowest there
 * for CTL_FALL_STALL_MS, every held limb is held low, for as long as one
 * falling limb is so held up: heated only below its band's upper edge (ψ* + h/2, not the hold
 * edge h/2 + margin above it), which still keeps its level, and off above it. A coil cooling
 * from its hold takes 0.2-1 s before its limb moves; 1.5 s leaves that room, and a held-up
 * limb 5 s of the default 8 s state timeout. */
#define CTL_FALL_STALL_MS 1500u
/* A fall still coming down (built with seq.h's SEQ_CLOCK_PAUSE: full strokes, or three or
 * more limbs). In a warm, still place a coil cools slowly through its hysteresis: R1 at full
 * strokes at 38 °C in an enclosure (convection ×0.6) took 8.5 s to come down from 11 to 00,
 * falling steadily at 3-12°/s, and the step ended in STATE_TIMEOUT 0.5 s short of 00. While
 * no limb rises, no coil is asked for more than the hold duty, and every limb not yet settled
 * at its target level is coming down and has had its smoothed ψ make a new low of its step
 * CTL_CLIMB_CDEG below the last within CTL_FALL_PROGRESS_MS, the step's time stands still
 * (seq.h seq_pause_clock, and the step guard's: safety.h). A limb that stops coming down
 * starts the clock again CTL_FALL_PROGRESS_MS later; new lows only count once per degree of
 * the step's fall, so a fall's pause is bounded by its height, not by noise (one wobbling
 * limb keeps finding its old lows). Nothing is heated past the hold in a paused tick, so the
 * coils' own step times (safety.h) and the envelope are untouched. */
#define CTL_FALL_PROGRESS_MS 1500u
#define CTL_STALL_NONE 0u
#define CTL_STALL_OSCILLATING 1u
#define CTL_STALL_UNREACHABLE 2u

/* target[i]: wanted level of limb i; drive_pm, hold_pm and duty[a], the result for
 * actuator a: permyriad. Call once per control tick (the stall detector counts calls). */
void ctl_demand(const uint8_t target[CFG_N_LIMBS], uint16_t drive_pm, uint16_t hold_pm,
                uint16_t duty[CFG_N_ACTUATORS]);

/* Forget every limb's step, hold and stall state. app_init calls it (after psi_init), so a
 * reset of the simulated board starts as cold as the chip's cleared RAM, and so does START. */
void ctl_reset(void);

/* CTL_STALL_* of limb i in its current step. */
uint8_t ctl_stall(uint8_t limb);

/* Actuator index driving limb i. */
uint8_t ctl_limb_actuator(uint8_t limb);

#if SEQ_CLOCK_PAUSE
/* The last ctl_demand found a fall still coming down (CTL_FALL_PROGRESS_MS); 0 after ctl_reset. */
uint8_t ctl_coming_down(void);
#endif

#endif /* PROLEG_CTL_H */
