/* Stub of the QuadDec (Quadrature Decoder) component API, instance "QuadDec",
 * counter size 32 bits (GetCounter/SetCounter take int32 at that size). */
#ifndef CY_QUADRATURE_DECODER_QuadDec_H
#define CY_QUADRATURE_DECODER_QuadDec_H

#include "cytypes.h"

void QuadDec_Start(void);
void QuadDec_Stop(void);
int32 QuadDec_GetCounter(void);
void QuadDec_SetCounter(int32 value);

#endif
