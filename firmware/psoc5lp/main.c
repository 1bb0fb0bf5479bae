/*
 * main.c - SFLR firmware for PSoC 5LP (CY8CKIT-059): protocol v1 over USB CDC,
 * one tick per 500 Hz interrupt. All decisions live in firmware/core; this file
 * only wires the interrupt and the main loop to it.
 */
#include "project.h"

#include "hal_psoc5lp.h"
#include "sflr_device.h"

static sflr_dev_t dev;

/* 500 Hz from Clock_tick: one protocol tick (choose, apply, latch, send). */
CY_ISR(tick_isr)
{
    hal_psoc5lp_tick(&dev);
}

int main(void)
{
    hal_psoc5lp_init(); /* amplifier disabled, DAC at 0 V, before anything else */
    sflr_init(&dev, &sflr_default_config);
    isr_tick_StartEx(tick_isr);
    CyGlobalIntEnable; /* USBUART_Start needs interrupts */
    USBUART_Start(0u, USBUART_5V_OPERATION);
    hal_psoc5lp_watchdog_start(); /* from here a hang or fault resets the chip */
    for (;;) {
        hal_psoc5lp_poll(&dev);
    }
}
