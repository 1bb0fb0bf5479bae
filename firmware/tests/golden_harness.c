/*
 * golden_harness.c - the device core driven line by line from stdin, for the Python
 * golden test (tests/test_device_golden.py) that compares it with the simulated device.
 * No timer: a tick happens when the test says so.
 *
 * Each input line is one step; each step answers exactly one output line with the
 * bytes the device sent during it, in hex (an empty line when it sent nothing):
 *   rx HEX             bytes from the station (sflr_rx_bytes)
 *   sensors THETA A    the raw encoder count and ADC reading the next latches see
 *   tick               one timer tick (sflr_tick)
 * An unknown line answers "error ..." and exits 2.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sflr_device.h"
#include "sflr_hal.h"

static int32_t raw_theta, theta_zero;
static int16_t raw_accel;
static uint8_t tx[4096];
static size_t tx_len;

int32_t hal_encoder_read(void) { return (int32_t)((uint32_t)raw_theta - (uint32_t)theta_zero); }
void hal_encoder_reset(void) { theta_zero = raw_theta; }
int16_t hal_accel_read(void) { return raw_accel; }
void hal_dac_write(int16_t v) { (void)v; }
void hal_amp_enable(bool on) { (void)on; }
void hal_uart_write(const uint8_t *data, size_t n)
{
    if (tx_len + n > sizeof tx) {
        fprintf(stderr, "golden_harness: tx buffer full\n");
        exit(3);
    }
    memcpy(tx + tx_len, data, n);
    tx_len += n;
}

static int hex_value(char c)
{
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
}

int main(void)
{
    static char line[16384];
    static uint8_t rx[8192];
    sflr_dev_t dev;
    sflr_init(&dev, &sflr_default_config);
    tx_len = 0; /* sflr_init sends nothing, but start clean */
    while (fgets(line, sizeof line, stdin) != NULL) {
        line[strcspn(line, "\r\n")] = '\0';
        long theta, accel;
        if (strncmp(line, "rx ", 3) == 0 || strcmp(line, "rx") == 0) {
            size_t n = 0;
            for (const char *p = line + 3 * (line[2] == ' '); p[0] && p[1]; p += 2) {
                int hi = hex_value(p[0]), lo = hex_value(p[1]);
                if (hi < 0 || lo < 0 || n == sizeof rx) {
                    printf("error bad hex\n");
                    return 2;
                }
                rx[n++] = (uint8_t)(hi * 16 + lo);
            }
            sflr_rx_bytes(&dev, rx, n);
        } else if (sscanf(line, "sensors %ld %ld", &theta, &accel) == 2) {
            raw_theta = (int32_t)theta;
            raw_accel = (int16_t)accel;
        } else if (strcmp(line, "tick") == 0) {
            sflr_tick(&dev);
        } else {
            printf("error unknown line: %s\n", line);
            return 2;
        }
        for (size_t i = 0; i < tx_len; i++) {
            printf("%02x", tx[i]);
        }
        printf("\n");
        fflush(stdout);
        tx_len = 0;
    }
    return 0;
}
