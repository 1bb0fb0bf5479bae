/* hal_psoc5lp.h - the core's HAL on PSoC 5LP components (see firmware/README.md). */
#ifndef HAL_PSOC5LP_H
#define HAL_PSOC5LP_H

#include "sflr_device.h"

/* Start the components with the amplifier disabled and the DAC at 0 V. */
void hal_psoc5lp_init(void);
/* Main-loop service: USB CDC enumeration, received bytes into the core (with the
 * tick interrupt masked), queued transmit bytes out. Never blocks. */
void hal_psoc5lp_poll(sflr_dev_t *dev);

#endif
