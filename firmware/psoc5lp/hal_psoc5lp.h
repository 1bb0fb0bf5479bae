/* hal_psoc5lp.h - the core's HAL on PSoC 5LP components (see firmware/README.md). */
#ifndef HAL_PSOC5LP_H
#define HAL_PSOC5LP_H

#include "sflr_device.h"

/* Start the components with the amplifier disabled and the DAC at 0 V. */
void hal_psoc5lp_init(void);
/* The tick interrupt's body: one protocol tick (sflr_tick), and a sign of life for the
 * hardware watchdog. */
void hal_psoc5lp_tick(sflr_dev_t *dev);
/* Start the hardware watchdog (32-48 ms, cannot be stopped once started): the main loop
 * feeds it only while the tick interrupt keeps running, so a hung main loop, a tick
 * interrupt that stopped, or a fault handler spinning with the amplifier enabled resets
 * the chip (pins high-impedance: AMP_EN's pull-down disables the amplifier). Build with
 * -DSFLR_NO_HW_WATCHDOG to debug with breakpoints. */
void hal_psoc5lp_watchdog_start(void);
/* Main-loop service: USB CDC enumeration, received bytes into the core (with the
 * tick interrupt masked), queued transmit bytes out, the watchdog fed. Never blocks. */
void hal_psoc5lp_poll(sflr_dev_t *dev);

#endif
