/* Stub of the DVDAC (dithered voltage DAC) component API, instance "DAC_N". */
#ifndef CY_DVDAC_DAC_N_H
#define CY_DVDAC_DAC_N_H

#include "cytypes.h"

void DAC_N_Start(void);
void DAC_N_Stop(void);
void DAC_N_SetValue(uint16 value);

#endif
