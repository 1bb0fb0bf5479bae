/* Stub of the Interrupt component API, instance "isr_tick". */
#ifndef CY_ISR_isr_tick_H
#define CY_ISR_isr_tick_H

#include "cytypes.h"

void isr_tick_Start(void);
void isr_tick_StartEx(cyisraddress address);
void isr_tick_Stop(void);

#endif
