/*
 * Minimal Cortex-M3 start-up for QEMU's mps2-an385 board (tests only).
 *
 * The vector table sits at address 0, where the core reads its initial stack
 * pointer and reset vector. The M3 has no FPU, so there is nothing to enable:
 * Reset_Handler enters newlib's rdimon start-up code (_start: zeroes .bss, sets
 * up semihosting, calls main, exits through semihosting with main's value).
 */
#include <stdint.h>

extern void _start(void);
extern void _exit(int status);
extern uint32_t __stack;

void Reset_Handler(void);
void Fault_Handler(void);

void Reset_Handler(void)
{
    _start();
    for (;;) {
    }
}

void Fault_Handler(void)
{
    _exit(70); /* semihosting exit: the test sees a failed run, not a hang */
}

__attribute__((section(".isr_vector"), used))
void (*const vector_table[16])(void) = {
    (void (*)(void))(&__stack), /* initial stack pointer */
    Reset_Handler,
    Fault_Handler, /* NMI */
    Fault_Handler, /* HardFault */
    Fault_Handler, /* MemManage */
    Fault_Handler, /* BusFault */
    Fault_Handler, /* UsageFault */
    0, 0, 0, 0,
    Fault_Handler, /* SVCall */
    Fault_Handler, /* DebugMonitor */
    0,
    Fault_Handler, /* PendSV */
    Fault_Handler, /* SysTick */
};
