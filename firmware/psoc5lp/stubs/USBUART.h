/* Stub of the USBFS component API configured as USBUART (CDC), instance "USBUART"
 * (the CDC functions live in USBUART_cdc.h in the generated sources). */
#ifndef CY_USBFS_USBUART_H
#define CY_USBFS_USBUART_H

#include "cytypes.h"

#define USBUART_3V_OPERATION 0x00u
#define USBUART_5V_OPERATION 0x01u
#define USBUART_DWR_VDDD_OPERATION 0x02u

void USBUART_Start(uint8 device, uint8 mode);
uint8 USBUART_GetConfiguration(void);
uint8 USBUART_IsConfigurationChanged(void);

/* USBUART_cdc.h */
uint8 USBUART_CDC_Init(void);
uint8 USBUART_DataIsReady(void);
uint16 USBUART_GetCount(void);
uint16 USBUART_GetAll(uint8 pData[]);
uint8 USBUART_CDCIsReady(void);
void USBUART_PutData(const uint8 pData[], uint16 length);

#endif
