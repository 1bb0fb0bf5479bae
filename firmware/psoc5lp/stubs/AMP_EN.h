/* Stub of the per-pin API of a Digital Output Pins component, instance "AMP_EN". */
#ifndef CY_PINS_AMP_EN_H
#define CY_PINS_AMP_EN_H

#include "cytypes.h"

void AMP_EN_Write(uint8 value);
uint8 AMP_EN_Read(void);

#endif
