/* limbmap.c - see limbmap.h. */
#include "limbmap.h"

#include "proto.h"

static const uint8_t compiled[CFG_N_LIMBS] ROM = CFG_LIMB_ACTUATOR;
static uint8_t map[CFG_N_LIMBS]; /* both set by limbmap_init (no .data bytes in flash) */
static uint8_t lost;

void limbmap_init(void)
{
    limbmap_use(LIMBMAP_NONE, compiled);
}

#if defined(__GNUC__)
__attribute__((noinline)) /* several callers: one copy */
#endif
uint8_t limbmap_actuator(uint8_t limb)
{
    return map[limb];
}

uint8_t limbmap_lost(void)
{
    return lost;
}

uint8_t limbmap_given_up(uint8_t limb)
{
    return (uint8_t)(ROM_U8(&compiled[limb]) == lost); /* never while none is: no actuator is LIMBMAP_NONE */
}

void limbmap_use(uint8_t lost_actuator, const uint8_t *rom_map)
{
    uint8_t i;
    for (i = 0; i < CFG_N_LIMBS; i++) {
        map[i] = ROM_U8(&rom_map[i]);
    }
    lost = lost_actuator;
}

uint8_t limbmap_set(const uint8_t *actuators, uint8_t n, uint16_t *bad)
{
    uint8_t i;
    if (n != 0u && n != CFG_N_LIMBS) {
        *bad = 0xFFFFu;
        return PROTO_ERR_OUT_OF_RANGE;
    }
    for (i = 0; i < n; i++) {
        if (actuators[i] >= CFG_N_ACTUATORS || (CFG_FALLBACK && actuators[i] == lost)) {
            *bad = i;
            return PROTO_ERR_OUT_OF_RANGE;
        }
    }
    if (n) {
        for (i = 0; i < CFG_N_LIMBS; i++) {
            map[i] = actuators[i];
        }
    } else {
        limbmap_use(LIMBMAP_NONE, compiled); /* the build's map, a coil the fallback gave up taken back (limbmap.h) */
    }
    return 0;
}
