/* Stub of the Clock component API, instance "Clock_tick" (500 Hz). */
#ifndef CY_CLOCK_Clock_tick_H
#define CY_CLOCK_Clock_tick_H

#include "cytypes.h"

void Clock_tick_Start(void);
void Clock_tick_Stop(void);

#endif
