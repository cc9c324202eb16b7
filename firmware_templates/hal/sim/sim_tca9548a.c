/* sim_tca9548a.c - see sim_tca9548a.h. Host code for the simulated board only. */
#include "sim_tca9548a.h"

#include <string.h>

typedef struct {
    uint8_t present;
    uint8_t bus;
    uint8_t addr;
    uint8_t control;
} tca_t;

static tca_t devs[SIM_TCA_MAX];
static uint32_t writes;

static tca_t *find(uint8_t bus, uint8_t addr)
{
    uint8_t i;
    for (i = 0; i < SIM_TCA_MAX; i++) {
        if (devs[i].present && devs[i].bus == bus && devs[i].addr == addr) {
            return &devs[i];
        }
    }
    return 0;
}

void sim_tca_power_on(void)
{
    memset(devs, 0, sizeof devs);
    writes = 0;
}

void sim_tca_attach(uint8_t bus, uint8_t addr)
{
    uint8_t i;
    if (addr < 0x70u || addr > 0x77u || find(bus, addr)) {
        return;
    }
    for (i = 0; i < SIM_TCA_MAX; i++) {
        if (!devs[i].present) {
            devs[i].present = 1;
            devs[i].bus = bus;
            devs[i].addr = addr;
            devs[i].control = 0;
            return;
        }
    }
}

int sim_tca_transfer(uint8_t bus, uint8_t addr, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx)
{
    tca_t *d = find(bus, addr);
    uint8_t i;
    if (!d) {
        return -1;
    }
    if (ntx > 0u) {
        d->control = tx[ntx - 1u];
        writes++;
    }
    for (i = 0; i < nrx; i++) {
        rx[i] = d->control;
    }
    return 0;
}

uint8_t sim_tca_enabled(uint8_t bus, uint8_t addr, uint8_t ch)
{
    tca_t *d = find(bus, addr);
    return (d && ch < 8u && (d->control & (1u << ch))) ? 1u : 0u;
}

uint8_t sim_tca_control(uint8_t bus, uint8_t addr)
{
    tca_t *d = find(bus, addr);
    return d ? d->control : 0u;
}

uint32_t sim_tca_writes(void)
{
    return writes;
}
