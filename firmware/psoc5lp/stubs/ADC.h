/* Stub of the ADC_DelSig component API, instance "ADC". */
#ifndef CY_ADC_DELSIG_ADC_H
#define CY_ADC_DELSIG_ADC_H

#include "cytypes.h"

#define ADC_RETURN_STATUS 1u
#define ADC_WAIT_FOR_RESULT 0u

void ADC_Start(void);
void ADC_Stop(void);
void ADC_StartConvert(void);
void ADC_StopConvert(void);
uint8 ADC_IsEndConversion(uint8 retMode);
int16 ADC_GetResult16(void);

#endif
