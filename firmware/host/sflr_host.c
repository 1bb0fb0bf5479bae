/*
 * sflr_host.c - firmware in the loop on a PC: the same core as the PSoC build,
 * ticking at 500 Hz on a pseudo-terminal, with a simulated motor and encoder
 * behind the HAL. A station opens the pty exactly like the rig's serial port.
 *
 *   sflr_host [--trace FILE] [--watchdog-ticks N] [--v-limit N] [--spring K]
 *
 * First stdout line: the pty slave path. --trace FILE writes one line per timer
 * tick: "t tick output enable status" (t = CLOCK_MONOTONIC seconds, tick = the
 * device tick whose SAMPLE went out or -1, output = DAC counts that tick applied (when
 * its SAMPLE went out; else after the tick), enable = amplifier enable at the same moment,
 * status = that SAMPLE's status or -1).
 * SIGTERM/SIGINT: output 0, amplifier off, trace flushed, exit 0.
 *
 * Threads mirror the target: the tick thread is the timer interrupt (absolute
 * clock_nanosleep deadlines, no drift); the main thread is the main loop feeding
 * received bytes. One mutex stands for "interrupts masked".
 */
#define _XOPEN_SOURCE 700 /* posix_openpt, ptsname, clock_nanosleep */
#define _DEFAULT_SOURCE    /* cfmakeraw */
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <poll.h>
#include <pthread.h>
#include <sched.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include "sflr_device.h"
#include "sflr_hal.h"

#define TICK_NS 2000000L /* 500 Hz */
#define SUBSTEPS 20

/* ------------------------------------------------------------ simulated rig */

/* Motor: angle/v = num/(s(s+p)) (the rig's actuator fit, DESIGN.md), plus a weak
 * centring spring (K, 1/s^2) so a held position needs a nonzero command and the
 * hold/watchdog behaviour is visible in the output. */
static const double ACT_P = 120.40659975047289;                  /* rad/s */
static const double ACT_NUM = 0.06727320631008038 * 120.57040; /* rad/s^2 per count, act_K*|2*pi*j+p| */
static const double H = 1024.0 / (2.0 * 3.14159265358979323846); /* counts/rad */
static double spring = 400.0;

static double angle, rate;     /* rad, rad/s */
static double encoder_zero;    /* rad at the last encoder reset */
static int16_t dac;            /* last DAC write */
static bool amp;               /* amplifier enable */
static uint32_t noise_state = 12345u;

static void plant_advance(double dt)
{
    double v = amp ? (double)dac : 0.0; /* a disabled amplifier drives no current */
    double h = dt / SUBSTEPS;
    for (int i = 0; i < SUBSTEPS; i++) { /* semi-implicit Euler, 100 us steps */
        rate += h * (ACT_NUM * v - ACT_P * rate - spring * angle);
        angle += h * rate;
    }
}

/* ------------------------------------------------------------ HAL */

static int master_fd = -1;
static unsigned long tx_dropped;
static bool sample_sent;
static sflr_msg_t last_sample;
static int16_t sample_dac; /* output and enable when the SAMPLE went out (n_ticks may end */
static bool sample_amp;    /* the run, output 0, later in the same tick) */

int32_t hal_encoder_read(void) { return (int32_t)lround((angle - encoder_zero) * H); }
void hal_encoder_reset(void) { encoder_zero = angle; }
int16_t hal_accel_read(void)
{
    noise_state = noise_state * 1664525u + 1013904223u; /* deterministic noise, -1..1 */
    return (int16_t)(-2 + (int)((noise_state >> 16) % 3u) - 1);
}
void hal_dac_write(int16_t v) { dac = v; }
void hal_amp_enable(bool on) { amp = on; }
void hal_uart_write(const uint8_t *data, size_t n)
{
    sflr_msg_t m;
    if (n > 1 && sflr_frame_decode(data, n - 1, &m) == SFLR_OK && m.type == SFLR_SAMPLE) {
        sample_sent = true; /* for the trace */
        last_sample = m;
        sample_dac = dac;
        sample_amp = amp;
    }
    /* Non-blocking, like a UART FIFO: with nobody reading, frames are dropped. */
    ssize_t w = write(master_fd, data, n);
    if (w != (ssize_t)n) {
        tx_dropped++;
    }
}

/* ------------------------------------------------------------ loop */

static pthread_mutex_t lock = PTHREAD_MUTEX_INITIALIZER;
static volatile sig_atomic_t stop_flag;
static sflr_dev_t dev;
static FILE *trace;
static unsigned long overruns;

static void on_signal(int sig) { (void)sig; stop_flag = 1; }

static void timespec_add_ns(struct timespec *t, long ns)
{
    t->tv_nsec += ns;
    while (t->tv_nsec >= 1000000000L) {
        t->tv_nsec -= 1000000000L;
        t->tv_sec++;
    }
}

static void *tick_thread(void *arg)
{
    (void)arg;
    struct timespec next;
    clock_gettime(CLOCK_MONOTONIC, &next);
    while (!stop_flag) {
        timespec_add_ns(&next, TICK_NS);
        while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, NULL) == EINTR) {
        }
        struct timespec now;
        clock_gettime(CLOCK_MONOTONIC, &now);
        if ((now.tv_sec - next.tv_sec) * 1000000000L + (now.tv_nsec - next.tv_nsec) > TICK_NS) {
            overruns++; /* woke more than a tick late; deadlines stay absolute */
        }
        char line[96];
        int len;
        pthread_mutex_lock(&lock);
        plant_advance(TICK_NS * 1e-9); /* the plant evolved under the last output */
        sample_sent = false;
        sflr_tick(&dev);
        len = snprintf(line, sizeof line, "%lld.%06ld %ld %d %d %d\n", (long long)now.tv_sec,
                       now.tv_nsec / 1000L, sample_sent ? (long)(dev.k - 1u) : -1L,
                       (int)(sample_sent ? sample_dac : dac), (sample_sent ? sample_amp : amp) ? 1 : 0,
                       sample_sent ? (int)last_sample.u.sample.status : -1);
        pthread_mutex_unlock(&lock);
        if (trace != NULL && len > 0) {
            fwrite(line, 1, (size_t)len, trace);
            fflush(trace);
        }
    }
    return NULL;
}

static void usage(void)
{
    fprintf(stderr, "usage: sflr_host [--trace FILE] [--watchdog-ticks N] [--v-limit N] [--spring K]\n");
    exit(2);
}

int main(int argc, char **argv)
{
    sflr_config_t cfg = sflr_default_config;
    const char *trace_path = NULL;
    for (int i = 1; i < argc; i++) {
        if (i + 1 >= argc) {
            usage();
        }
        if (strcmp(argv[i], "--trace") == 0) {
            trace_path = argv[++i];
        } else if (strcmp(argv[i], "--watchdog-ticks") == 0) {
            cfg.watchdog_ticks = (uint8_t)atoi(argv[++i]);
        } else if (strcmp(argv[i], "--v-limit") == 0) {
            cfg.v_limit = (int16_t)atoi(argv[++i]);
        } else if (strcmp(argv[i], "--spring") == 0) {
            spring = atof(argv[++i]);
        } else {
            usage();
        }
    }

    master_fd = posix_openpt(O_RDWR | O_NOCTTY);
    if (master_fd < 0 || grantpt(master_fd) != 0 || unlockpt(master_fd) != 0) {
        perror("sflr_host: pty");
        return 1;
    }
    const char *slave_path = ptsname(master_fd);
    /* Hold the slave open (so reads never see EIO between stations) in raw mode:
     * no echo, no line editing, 8-bit clean. */
    int slave_fd = slave_path ? open(slave_path, O_RDWR | O_NOCTTY) : -1;
    struct termios tio;
    if (slave_fd < 0 || tcgetattr(slave_fd, &tio) != 0) {
        perror("sflr_host: slave");
        return 1;
    }
    cfmakeraw(&tio);
    tcsetattr(slave_fd, TCSANOW, &tio);
    fcntl(master_fd, F_SETFL, fcntl(master_fd, F_GETFL) | O_NONBLOCK);

    if (trace_path != NULL) {
        trace = fopen(trace_path, "w");
        if (trace == NULL) {
            perror("sflr_host: trace");
            return 1;
        }
        fprintf(trace, "# t tick output enable status\n");
    }

    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal; /* no SA_RESTART: poll() returns EINTR */
    sigaction(SIGTERM, &sa, NULL);
    sigaction(SIGINT, &sa, NULL);

    sflr_init(&dev, &cfg);

    /* Signals go to the main thread only. */
    sigset_t block, old;
    sigemptyset(&block);
    sigaddset(&block, SIGTERM);
    sigaddset(&block, SIGINT);
    pthread_sigmask(SIG_BLOCK, &block, &old);
    /* The tick thread is the "interrupt": real-time priority when allowed
     * (root / CAP_SYS_NICE), else an ordinary thread on a busy host. */
    pthread_t tid;
    pthread_attr_t attr;
    struct sched_param prio = { .sched_priority = 50 };
    pthread_attr_init(&attr);
    pthread_attr_setinheritsched(&attr, PTHREAD_EXPLICIT_SCHED);
    pthread_attr_setschedpolicy(&attr, SCHED_FIFO);
    pthread_attr_setschedparam(&attr, &prio);
    if (pthread_create(&tid, &attr, tick_thread, NULL) != 0 && pthread_create(&tid, NULL, tick_thread, NULL) != 0) {
        perror("sflr_host: thread");
        return 1;
    }
    pthread_attr_destroy(&attr);
    pthread_sigmask(SIG_SETMASK, &old, NULL);
    /* The UART receive is an interrupt on the MCU too: this reader gets a real-time class
     * just below the tick's when allowed, or on a busy host commands wait behind ordinary
     * load (and the tick thread behind the lock this thread holds) and tick LATE. */
    struct sched_param rx_prio = { .sched_priority = 49 };
    (void)pthread_setschedparam(pthread_self(), SCHED_FIFO, &rx_prio);

    printf("%s\n", slave_path);
    fflush(stdout);

    while (!stop_flag) {
        struct pollfd p = { .fd = master_fd, .events = POLLIN, .revents = 0 };
        int r = poll(&p, 1, 100);
        if (r <= 0) {
            continue; /* timeout or EINTR */
        }
        uint8_t buf[256];
        ssize_t n = read(master_fd, buf, sizeof buf);
        if (n > 0) {
            pthread_mutex_lock(&lock);
            sflr_rx_bytes(&dev, buf, (size_t)n);
            pthread_mutex_unlock(&lock);
        } else if (n < 0 && errno != EAGAIN && errno != EINTR) {
            usleep(10000); /* EIO: no slave; cannot happen while we hold it, but never spin */
        }
    }

    pthread_join(tid, NULL);
    hal_dac_write(0); /* leave the (simulated) rig safe */
    hal_amp_enable(false);
    if (trace != NULL) {
        struct timespec now;
        clock_gettime(CLOCK_MONOTONIC, &now);
        fprintf(trace, "%lld.%06ld -1 0 0 -1\n", (long long)now.tv_sec, now.tv_nsec / 1000L);
        fclose(trace);
    }
    fprintf(stderr, "sflr_host: exit (tick overruns %lu, tx frames dropped %lu, rx errors %u)\n", overruns,
            tx_dropped, (unsigned)dev.rx_errors);
    close(slave_fd);
    close(master_fd);
    return 0;
}
