"""The STM32F103C8's memory map and core clock as the arm-emu board uses them."""

from __future__ import annotations

from .clocks import CPU_HZ

FLASH_BASE, FLASH_SIZE = 0x08000000, 0x10000
RAM_BASE, RAM_SIZE = 0x20000000, 0x5000
USART1_IRQ = 37
CYC_PER_US = CPU_HZ // 1_000_000
