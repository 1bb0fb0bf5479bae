/* Stub of the DVDAC (dithered voltage DAC) component API, instance "DAC_P". */
#ifndef CY_DVDAC_DAC_P_H
#define CY_DVDAC_DAC_P_H

#include "cytypes.h"

void DAC_P_Start(void);
void DAC_P_Stop(void);
void DAC_P_SetValue(uint16 value);

#endif
