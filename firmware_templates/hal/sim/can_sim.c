/* can_sim.c - the simulated board's CAN controller (images with [link] transport = "can").
 *
 * What the host sees is the bus: frames the firmware queued (canlink.h) leave at the board
 * file's bit rate, one per CAN_FRAME_BITS bit times (an 8-byte frame with worst-case bit
 * stuffing and the interframe space, ISO 11898-1), into a host queue that
 * sim_can_read empties; sim_can_write delivers a frame from the bus, and, as the bxCAN's
 * acceptance filter does, only this node's command identifier reaches the firmware.
 * sim_can_drain runs once per tick from sim_run_ticks (hal_sim.c).
 */
#include <string.h>

#include "canlink.h"
#include "hal.h"
#include "robot_config.h"

#define SIM_API __attribute__((visibility("default")))
#define HOSTQ_FRAMES 4096u
#define CAN_FRAME_BITS 135u

void sim_can_drain(void);

static can_frame_t hostq[HOSTQ_FRAMES];
static uint32_t hostq_head, hostq_count, dropped;
static uint64_t bus_budget; /* bit times × 1e6 the bus may still carry */

void hal_can_init(void)
{
    hostq_head = 0;
    hostq_count = 0;
    dropped = 0;
    bus_budget = 0;
}

void hal_can_tx_start(void)
{
    /* nothing to switch on: sim_can_drain moves queued frames at the bit rate */
}

void sim_can_drain(void)
{
    can_frame_t f;
    bus_budget += (uint64_t)CFG_CAN_BITRATE * CFG_TICK_US;
    while (bus_budget >= (uint64_t)CAN_FRAME_BITS * 1000000u) {
        if (canlink_isr_tx(&f) < 0) {
            break;
        }
        if (hostq_count < HOSTQ_FRAMES) {
            hostq[(hostq_head + hostq_count) % HOSTQ_FRAMES] = f;
            hostq_count++;
        } else {
            dropped++;
        }
        bus_budget -= (uint64_t)CAN_FRAME_BITS * 1000000u;
    }
    if (bus_budget > (uint64_t)CAN_FRAME_BITS * 1000000u) {
        bus_budget = (uint64_t)CAN_FRAME_BITS * 1000000u; /* an idle bus stores no credit */
    }
}

/* A frame on the bus: the acceptance filter passes this node's CMD identifier only. */
SIM_API void sim_can_write(uint16_t id, const uint8_t *data, uint8_t dlc)
{
    if (dlc > 8u) {
        dlc = 8u;
    }
    if (id == CANLINK_ID(CANLINK_SLOT_CMD)) {
        canlink_isr_rx(id, data, dlc);
    }
}

/* The oldest frame the firmware put on the bus: 1 and *id, data[8], *dlc; 0 when none. */
SIM_API uint32_t sim_can_read(uint16_t *id, uint8_t *data, uint8_t *dlc)
{
    const can_frame_t *f;
    if (hostq_count == 0u) {
        return 0;
    }
    f = &hostq[hostq_head];
    *id = f->id;
    *dlc = f->dlc;
    memcpy(data, f->data, 8);
    hostq_head = (hostq_head + 1u) % HOSTQ_FRAMES;
    hostq_count--;
    return 1;
}

SIM_API uint32_t sim_can_bitrate(void)
{
    return CFG_CAN_BITRATE;
}

SIM_API uint32_t sim_can_node(void)
{
    return ((uint32_t)CFG_CAN_BASE_ID << 8) | CFG_CAN_NODE;
}
