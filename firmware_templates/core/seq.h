/* seq.h - the gait sequencer.
 *
 * Contract. A gait is a closed walk of robot states; the sequencer holds the current
 * step's target state. Each tick it gets the measured (debounced) state: when it equals
 * the target for hold ticks in a row, the next step's state becomes the target; when a
 * step has spent the state timeout away from its target (before reaching it, or after
 * losing it: ticks at the target, held, never count), it stops and reports SEQ_EV_TIMEOUT
 * (e.g. a dead actuator). Gaits come from the rendered gait table (gait_table.c: the
 * optimal gaits per direction, every tie) or from one gait loaded at run time, which is
 * checked against the robot's allowed transitions and the length limit first.
 * A start begins at the measured state's position in the gait when it is on the walk;
 * from rest (state 0) off the walk, a rendered gait is entered through its entry path
 * (gait_table.c: the states between rest and the gait's join step, over allowed
 * transitions, proleg.gait.feasibility.entry_path), then run from the join step.
 */
#ifndef PROLEG_SEQ_H
#define PROLEG_SEQ_H

#include <stdint.h>

#include "robot_config.h"
#include "rom.h"

#define SEQ_DIR_PX 0u     /* +x */
#define SEQ_DIR_MX 1u     /* -x */
#define SEQ_DIR_LOADED 2u /* the gait loaded with seq_load */

#define SEQ_STEP_ENTRY 0xFFFFu /* seq_step() on the entry path from rest */

#define SEQ_EV_REACHED 0x01u  /* target state of this step reached (once per step) */
#define SEQ_EV_ADVANCED 0x02u /* held long enough: next step */
#define SEQ_EV_CYCLE 0x04u    /* a whole cycle completed */
#define SEQ_EV_TIMEOUT 0x08u  /* step not completed in time: stopped */
#define SEQ_EV_AWAY 0x10u     /* not at the target: before it is reached, or after it was lost */

#define SEQ_OK 0
#define SEQ_ERR_LENGTH (-1)    /* no steps, or more than CFG_MAX_LOADED_STEPS */
#define SEQ_ERR_STATE (-2)     /* a state index ≥ CFG_N_STATES */
#define SEQ_ERR_FORBIDDEN (-3) /* a transition the robot cannot make */
#define SEQ_ERR_NO_GAIT (-4)   /* no such gait (direction, index) or nothing loaded */

/* Rendered in gait_table.c. */
extern const cfg_state_t seq_steps[] ROM;
extern const uint16_t seq_gait_first[] ROM;
extern const uint16_t seq_gait_len[] ROM;
/* Entry from rest per rendered gait: states seq_entry_steps[first .. first+len), then
 * the gait from step seq_entry_join. */
extern const cfg_state_t seq_entry_steps[] ROM;
extern const uint16_t seq_entry_first[] ROM;
extern const uint16_t seq_entry_len[] ROM;
extern const uint16_t seq_entry_join[] ROM;
#if CFG_TRANS_BITMAP
extern const uint8_t seq_allowed[] ROM;
#else
extern const uint32_t seq_edges[] ROM;
#endif

void seq_init(void);
void seq_set_hold(uint32_t ticks);    /* target held this long → next step */
void seq_set_timeout(uint32_t ticks); /* step not done in this long → SEQ_EV_TIMEOUT */

/* Built where falls are long (a limb with a full stroke) or held up by neighbours (three or
 * more limbs): the ticks a fall still comes down (ctl.h, CTL_FALL_PROGRESS_MS) do not count
 * toward the step's timeout. paused: from the next seq_tick on, until told otherwise; a new
 * step or START does not change it (drive.c tells it every tick). */
#if defined(CFG_LIMB_STROKE_CDEG) || CFG_N_LIMBS > 2
#define SEQ_CLOCK_PAUSE 1
void seq_pause_clock(uint8_t paused);
#else
#define SEQ_CLOCK_PAUSE 0
#endif

/* 1 when a → b is an allowed transition (a ≠ b). */
uint8_t seq_allowed_transition(cfg_state_t a, cfg_state_t b);

/* Number of rendered gaits in a direction (SEQ_DIR_PX / SEQ_DIR_MX). */
uint8_t seq_gait_count(uint8_t dir);

/* Check and store a gait (open or closed: a repeated first state at the end is dropped).
 * On SEQ_ERR_FORBIDDEN, *bad is the step index whose transition to the next is forbidden
 * (a one-state walk, e.g. 2 2 closed, follows itself: step 0). */
int8_t seq_load(const cfg_state_t *states, uint16_t n, uint16_t *bad);

/* Start gait `index` of `dir`, or the loaded gait with SEQ_DIR_LOADED; `measured` is
 * the current state (any value ≥ CFG_N_STATES: unknown, start at step 0). */
int8_t seq_start(uint8_t dir, uint8_t index, uint16_t measured);
void seq_stop(void);

/* One control tick with the measured state; returns SEQ_EV_* flags. */
uint8_t seq_tick(cfg_state_t measured);

uint8_t seq_running(void);
uint8_t seq_holding(void); /* running and the current target measured now (not just reached once) */
cfg_state_t seq_target(void);
uint16_t seq_step(void); /* SEQ_STEP_ENTRY while on the entry path (events show 255) */
uint8_t seq_step_byte(void); /* seq_step() as EVENT and TELEMETRY carry it: 255 from 255 up and on the entry path */
uint32_t seq_cycles(void);

/* State index ↔ per-limb levels (first limb most significant digit). */
void seq_state_levels(cfg_state_t state, uint8_t levels[CFG_N_LIMBS]);
cfg_state_t seq_state_index(const uint8_t levels[CFG_N_LIMBS]);

#endif /* PROLEG_SEQ_H */
