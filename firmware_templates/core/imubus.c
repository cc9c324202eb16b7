/* imubus.c - see imubus.h. */
#include "imubus.h"

#include "hal.h"
#include "initzero.h"
#include "rom.h"

#if CFG_I2C_BUSES > 1
static const uint8_t limb_bus[CFG_N_LIMBS] ROM = CFG_LIMB_IMU_BUS;
#endif
#if CFG_IMU_MUX_USED
static const uint8_t limb_mux[CFG_N_LIMBS] ROM = CFG_LIMB_IMU_MUX;
static const uint8_t limb_channel[CFG_N_LIMBS] ROM = CFG_LIMB_IMU_CHANNEL;
#endif

#define STEP_NONE 0u
#define STEP_SELECT 1u /* the multiplexer's control byte is on the bus */

/* All zero is the power-on state: no transaction, no channel known. */
static struct {
#if CFG_IMU_MUX_USED
    uint8_t step;
    uint8_t bus;                    /* the transaction's bus */
    uint8_t ch;                     /* channel being selected */
    uint8_t ctrl;                   /* the control byte on the bus (must outlive the transfer) */
    uint8_t addr, ntx, nrx;         /* the IMU transaction that follows the select */
    const uint8_t *tx;
    uint8_t *rx;
    uint8_t channel[CFG_I2C_BUSES]; /* enabled multiplexer channel + 1 per bus, 0 = not known */
#endif
    uint32_t switches;
} st;

static int8_t begin_on(uint8_t bus, uint8_t addr7, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx)
{
#if CFG_I2C_BUSES > 1
    return hal_i2c_begin_bus(bus, addr7, tx, ntx, rx, nrx);
#else
    (void)bus; /* one bus: hal_i2c_begin, so a one-bus HAL needs nothing else */
    return hal_i2c_begin(addr7, tx, ntx, rx, nrx);
#endif
}

void imubus_init(void)
{
    INIT_ZERO(st);
}

int8_t imubus_begin(uint8_t limb, uint8_t addr7, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx)
{
    uint8_t bus = 0;
    if (limb >= CFG_N_LIMBS) {
        return -1;
    }
#if CFG_IMU_MUX_USED
    if (st.step != STEP_NONE) {
        return -1; /* one transaction at a time: a select is still in flight */
    }
#endif
#if CFG_I2C_BUSES > 1
    bus = ROM_U8(&limb_bus[limb]);
#endif
#if CFG_IMU_MUX_USED
    {
        uint8_t mux = ROM_U8(&limb_mux[limb]);
        uint8_t ch = ROM_U8(&limb_channel[limb]);
        if (mux != 0u && st.channel[bus] != (uint8_t)(ch + 1u)) {
            st.ctrl = (uint8_t)(1u << ch);
            if (begin_on(bus, mux, &st.ctrl, 1, (uint8_t *)0, 0) != 0) {
                return -1;
            }
            st.switches++;
            st.channel[bus] = 0; /* not known until the write is ACKed */
            st.bus = bus;
            st.ch = ch;
            st.addr = addr7;
            st.tx = tx;
            st.ntx = ntx;
            st.rx = rx;
            st.nrx = nrx;
            st.step = STEP_SELECT;
            return 0;
        }
    }
#endif
    if (begin_on(bus, addr7, tx, ntx, rx, nrx) != 0) {
        return -1;
    }
    return 0;
}

int8_t imubus_poll(void)
{
    int8_t r = hal_i2c_poll();
#if CFG_IMU_MUX_USED
    if (st.step == STEP_SELECT && r != HAL_I2C_BUSY) {
        st.step = STEP_NONE;
        if (r != 0) {
            return -1; /* the multiplexer did not ACK: the IMU is not read through a wrong channel */
        }
        st.channel[st.bus] = (uint8_t)(st.ch + 1u);
        if (begin_on(st.bus, st.addr, st.tx, st.ntx, st.rx, st.nrx) != 0) {
            return -1;
        }
        r = hal_i2c_poll(); /* a HAL that completes at once (host-sim) has the result now */
    }
#endif
    return r; /* the IMU's own transaction (hal.h semantics) */
}

uint32_t imubus_switches(void)
{
    return st.switches;
}
