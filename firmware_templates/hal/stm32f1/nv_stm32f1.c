/* nv_stm32f1.c - hal_nv_read/write/poll on the STM32F103: the last flash page.
 * Part of the stm32f1 HAL (hal_stm32f1.h).
 *
 * The block is the start of the last 1 KiB page of the 64 KiB flash (0x0800FC00; the
 * linker script leaves that page out). Programmed through the FPEC (RM0008 §3.3.3;
 * PM0075 §2.3): unlock with KEY1/KEY2, page erase (PER, AR, STRT), then PG and one
 * half-word store at a time, BSY polled after each (erase ≤ 40 ms, program ≤ 70 µs per
 * half-word: DS5319 table 28; the CPU stalls on its flash fetches meanwhile), lock again.
 * The whole write happens in hal_nv_write: the core writes only while no gait runs. The
 * watchdog (33-67 ms) could bite during a 40 ms erase: its prescaler goes from /8 to /16
 * (≥ 66 ms) for the write and back after (RM0008 §19.3.4: PR may change while it runs). */
#include <stdint.h>

#include "hal.h"
#include "hal_stm32f1.h"

#define NV_PAGE 0x0800FC00u
#define FLASH_KEYR REG32(0x40022004u)
#define FLASH_SR REG32(0x4002200Cu)
#define FLASH_CR REG32(0x40022010u)
#define FLASH_AR REG32(0x40022014u)
#define FLASH_SR_BSY (1u << 0)
#define FLASH_SR_ERR ((1u << 2) | (1u << 4)) /* PGERR, WRPRTERR */
#define FLASH_SR_EOP (1u << 5)
#define FLASH_CR_PG (1u << 0)
#define FLASH_CR_PER (1u << 1)
#define FLASH_CR_STRT (1u << 6)
#define FLASH_CR_LOCK (1u << 7)

static int8_t nv_result;

static int8_t fpec_wait(void)
{
    uint32_t n = 0;
    while (FLASH_SR & FLASH_SR_BSY) {
        if (++n > 4000000u) { /* far beyond the 40 ms erase at 72 MHz */
            return -1;
        }
    }
    n = FLASH_SR;
    FLASH_SR = FLASH_SR_ERR | FLASH_SR_EOP; /* write 1 to clear */
    return (n & FLASH_SR_ERR) ? -1 : 0;
}

void hal_nv_read(uint8_t *dst, uint8_t n)
{
    const volatile uint8_t *p = (const volatile uint8_t *)NV_PAGE;
    uint8_t i;
    for (i = 0; i < n && i < HAL_NV_BYTES; i++) {
        dst[i] = p[i];
    }
}

int8_t hal_nv_write(const uint8_t *src, uint8_t n)
{
    volatile uint16_t *p = (volatile uint16_t *)NV_PAGE;
    uint8_t i;
    int8_t r;
    uint16_t h;
    if (n > HAL_NV_BYTES) {
        return -1;
    }
    IWDG_KR = 0x5555u;
    IWDG_PR = 2u; /* /16 */
    IWDG_KR = 0xAAAAu;
    if (FLASH_CR & FLASH_CR_LOCK) {
        FLASH_KEYR = 0x45670123u;
        FLASH_KEYR = 0xCDEF89ABu;
    }
    r = fpec_wait();
    FLASH_CR = FLASH_CR_PER;
    FLASH_AR = NV_PAGE;
    FLASH_CR = FLASH_CR_PER | FLASH_CR_STRT;
    r |= fpec_wait();
    FLASH_CR = FLASH_CR_PG;
    for (i = 0; i < n && r == 0; i += 2u) {
        h = (uint16_t)(src[i] | ((i + 1u < n ? src[i + 1u] : 0xFFu) << 8));
        if (h != 0xFFFFu) { /* erased already; programming 0xFFFF is pointless */
            p[i / 2u] = h;
            r |= fpec_wait();
        }
    }
    FLASH_CR = FLASH_CR_LOCK;
    IWDG_KR = 0xAAAAu;
    IWDG_KR = 0x5555u;
    IWDG_PR = 1u; /* /8 again */
    nv_result = r;
    return 0;
}

int8_t hal_nv_poll(void)
{
    return nv_result;
}
