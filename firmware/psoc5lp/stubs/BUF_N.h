/* Stub of the Opamp component API, instance "BUF_N" (voltage follower). */
#ifndef CY_OPAMP_BUF_N_H
#define CY_OPAMP_BUF_N_H

#include "cytypes.h"

void BUF_N_Start(void);
void BUF_N_Stop(void);

#endif
