/* Stub of PSoC Creator's CyLib.h (subset). */
#ifndef CY_BOOT_CYLIB_H
#define CY_BOOT_CYLIB_H

#include "cytypes.h"

#define CyGlobalIntEnable do { __asm("CPSIE   i"); } while (0)
#define CyGlobalIntDisable do { __asm("CPSID   i"); } while (0)

uint8 CyEnterCriticalSection(void);
void CyExitCriticalSection(uint8 savedIntrStatus);

#endif
