/* Stub of the Opamp component API, instance "BUF_P" (voltage follower). */
#ifndef CY_OPAMP_BUF_P_H
#define CY_OPAMP_BUF_P_H

#include "cytypes.h"

void BUF_P_Start(void);
void BUF_P_Stop(void);

#endif
