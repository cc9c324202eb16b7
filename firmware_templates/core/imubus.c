/* imubus.c - see imubus.h. */
#include "imubus.h"

#include <string.h>

#include "hal.h"
#include "rom.h"

static const uint8_t limb_bus[CFG_N_LIMBS] ROM = CFG_LIMB_IMU_BUS;
#if CFG_IMU_MUX_USED
static const uint8_t limb_mux[CFG_N_LIMBS] ROM = CFG_LIMB_IMU_MUX;
static const uint8_t limb_channel[CFG_N_LIMBS] ROM = CFG_LIMB_IMU_CHANNEL;
#endif

/* All zero is the power-on state: bus 0, no failed select, no channel known. */
static struct {
    uint8_t bus;                    /* the selected limb's bus */
    uint8_t failed;                 /* the last select failed */
    uint8_t channel[CFG_I2C_BUSES]; /* enabled multiplexer channel + 1 per bus, 0 = not known */
    uint32_t switches;
} st;

/* One transaction on bus 0, waited for: hal_i2c_poll() gives up by itself past
 * HAL_I2C_DEADLINE_US (hal.h), so the wait is bounded. Used only for the one-byte
 * multiplexer select, between ticks. */
static int bus0_write_read(uint8_t addr7, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx)
{
    int8_t r;
    if (hal_i2c_begin(addr7, tx, ntx, rx, nrx) != 0) {
        return -1;
    }
    while ((r = hal_i2c_poll()) == HAL_I2C_BUSY) {
    }
    return r == 0 ? 0 : -1;
}

static int bus_write_read(uint8_t bus, uint8_t addr7, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx)
{
#if CFG_I2C_BUSES > 1
    if (bus != 0u) {
        return hal_i2c_write_read_bus(bus, addr7, tx, ntx, rx, nrx);
    }
#else
    (void)bus;
#endif
    return bus0_write_read(addr7, tx, ntx, rx, nrx);
}

void imubus_init(void)
{
    memset(&st, 0, sizeof st);
}

int8_t imubus_select(uint8_t limb)
{
    if (limb >= CFG_N_LIMBS) {
        st.failed = 1;
        return -1;
    }
    st.bus = ROM_U8(&limb_bus[limb]);
    st.failed = 0;
#if CFG_IMU_MUX_USED
    {
        uint8_t mux = ROM_U8(&limb_mux[limb]);
        uint8_t ch = ROM_U8(&limb_channel[limb]);
        if (mux != 0u && st.channel[st.bus] != (uint8_t)(ch + 1u)) {
            uint8_t ctrl = (uint8_t)(1u << ch);
            st.switches++;
            if (bus_write_read(st.bus, mux, &ctrl, 1, (uint8_t *)0, 0) != 0) {
                st.channel[st.bus] = 0; /* not known: write it again next time */
                st.failed = 1;
                return -1;
            }
            st.channel[st.bus] = (uint8_t)(ch + 1u);
        }
    }
#endif
    return 0;
}

int imubus_write_read(uint8_t addr7, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx)
{
    if (st.failed) {
        return -1;
    }
    return bus_write_read(st.bus, addr7, tx, ntx, rx, nrx);
}

uint8_t imubus_on_second_bus(void)
{
    return st.bus != 0u;
}

uint32_t imubus_switches(void)
{
    return st.switches;
}
