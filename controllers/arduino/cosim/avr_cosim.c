/* avr_cosim.c: the amr-twin's bridge to libsimavr (simavr 1.6), loaded with ctypes by
 * controllers/avr_board.py.
 *
 * One ATmega2560 running an ELF, advanced cycle-accurately to a given cycle by cosim_run().
 * Inputs are queued with their cycle and applied by simavr cycle timers at that cycle (so they
 * land at the right instruction even while the core sleeps):
 *   - pin edges (cosim_queue_edge): toggle a digital input pin (the SC signals on INT4/INT5);
 *   - UART bytes (cosim_queue_rx): each byte enters USART0's receiver at the start of its
 *     frame on the wire; simavr raises RXC one byte time later.
 * Outputs read after a run:
 *   - cosim_outputs(): one byte per watched pin: for a pin whose timer compare output is
 *     connected (analogWrite 1..254) the OCR value, else 255 or 0 for its PORT bit (analogWrite
 *     0/255 and digitalWrite end up there, as in wiring_analog.c);
 *   - cosim_tx_take(): the bytes the firmware wrote to UDR0, with the cycle of each write.
 * simavr's UART counts 11 bits per byte (it adds a parity bit that 8N1 does not have): after
 * each baud change the byte time is set back to 10 bit times. simavr's console echo and its
 * usleep() on status polling are switched off; sleep does not wait in real time; external
 * interrupts in low-level mode are not re-polled every cycle; the phase-correct PWM modes
 * simavr 1.6 lacks are filled in (see patch_timers).
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <stdarg.h>

#include <simavr/sim_avr.h>
#include <simavr/sim_elf.h>
#include <simavr/sim_io.h>
#include <simavr/sim_irq.h>
#include <simavr/sim_cycle_timers.h>
#include <simavr/avr_ioport.h>
#include <simavr/avr_uart.h>
#include <simavr/avr_extint.h>
#include <simavr/avr_timer.h>

#define MAX_PINS 16

typedef struct {
    uint64_t cycle;
    uint8_t value;
} event_t;

typedef struct {
    event_t *buf;
    size_t head, tail, cap;
} queue_t;

typedef struct {
    uint16_t port;      /* PORTx data address */
    uint8_t bit;
    uint16_t tccr;      /* TCCRnA address, 0: not a PWM pin */
    uint8_t com_mask;   /* COMnx1 bit in TCCRnA */
    uint16_t ocr;       /* OCRnx (low byte) address */
} out_pin_t;

typedef struct cosim {
    avr_t *avr;
    elf_firmware_t *fw;
    avr_uart_t *uart;
    avr_irq_t *uart_in;
    out_pin_t out[MAX_PINS];
    int n_out;
    avr_irq_t *in_irq[MAX_PINS];
    uint8_t in_level[MAX_PINS];
    int n_in;
    queue_t edges;      /* value = input index to toggle */
    queue_t rx;         /* value = byte */
    event_t *tx;
    size_t n_tx, cap_tx;
    uint64_t stop_cycle;
    int stop;
    uint32_t baud_key;  /* UBRR | U2X << 16 seen last */
} cosim_t;

static char g_log[512];

static void logger(avr_t *avr, const int level, const char *format, va_list ap) {
    (void)avr;
    if (level <= LOG_WARNING)
        vsnprintf(g_log, sizeof(g_log), format, ap);
}

const char *cosim_last_log(void) { return g_log; }

static void no_sleep(avr_t *avr, avr_cycle_count_t how_long) { (void)avr; (void)how_long; }

static int push(queue_t *q, uint64_t cycle, uint8_t value) {
    if (q->tail == q->cap) {
        if (q->head > 0) {
            memmove(q->buf, q->buf + q->head, (q->tail - q->head) * sizeof(event_t));
            q->tail -= q->head;
            q->head = 0;
        } else {
            size_t cap = q->cap ? 2 * q->cap : 256;
            event_t *b = realloc(q->buf, cap * sizeof(event_t));
            if (!b) return -1;
            q->buf = b;
            q->cap = cap;
        }
    }
    q->buf[q->tail].cycle = cycle;
    q->buf[q->tail].value = value;
    q->tail++;
    return 0;
}

static void fix_uart_byte_time(cosim_t *s) {
    /* 10 bit times per byte (8N1) instead of simavr 1.6's 11 */
    avr_t *avr = s->avr;
    avr_uart_t *u = s->uart;
    uint32_t ubrr = avr_regbit_get(avr, u->ubrrl) | (avr_regbit_get(avr, u->ubrrh) << 8);
    uint32_t u2x = avr_regbit_get(avr, u->u2x);
    uint32_t key = ubrr | (u2x << 16) | (1u << 20);
    if (key == s->baud_key) return;
    s->baud_key = key;
    uint64_t cycles_per_bit = (uint64_t)(ubrr + 1) * (u2x ? 8 : 16);
    u->cycles_per_byte = cycles_per_bit * 10;
}

static void patch_timers(avr_t *avr) {
    /* simavr 1.6 has no phase-correct PWM (WGM 1-3 of the 16-bit timers, WGM 1 and 5 of the
     * 8-bit ones): such a timer gets TOP = 0 and raises its overflow and compare flags every
     * prescaler tick (half a million a second for each of timers 1-5, which Arduino's init()
     * puts in WGM 1). Those modes are mapped to simavr's nearest, counting up to the same TOP
     * (255, 511, 1023, OCRnA): the duty registers are the same, the PWM period is about half.
     * The twin reads the duty from OCRnx, and the thesis sketch uses no interrupt of these. */
    for (avr_io_t *io = avr->io_port; io; io = io->next) {
        if (strcmp(io->kind, "timer") != 0) continue;
        avr_timer_t *t = (avr_timer_t *)io;
        int sixteen = t->wgm_op[0].size == 16;
        avr_timer_wgm_t fc8 = AVR_TIMER_WGM_FCPWM8(), fc9 = AVR_TIMER_WGM_FCPWM9(),
                        fc10 = AVR_TIMER_WGM_FCPWM10(), oc = AVR_TIMER_WGM_OCPWM();
        if (t->wgm_op[1].kind == avr_timer_wgm_none) t->wgm_op[1] = fc8;
        if (sixteen) {
            if (t->wgm_op[2].kind == avr_timer_wgm_none) t->wgm_op[2] = fc9;
            if (t->wgm_op[3].kind == avr_timer_wgm_none) t->wgm_op[3] = fc10;
        } else if (t->wgm_op[5].kind == avr_timer_wgm_none) {
            t->wgm_op[5] = oc;
        }
    }
}

static avr_cycle_count_t edge_timer(avr_t *avr, avr_cycle_count_t when, void *param) {
    cosim_t *s = param;
    (void)when;
    queue_t *q = &s->edges;
    while (q->head < q->tail && q->buf[q->head].cycle <= avr->cycle) {
        int i = q->buf[q->head].value;
        s->in_level[i] ^= 1;
        avr_raise_irq(s->in_irq[i], s->in_level[i]);
        q->head++;
    }
    if (q->head == q->tail) {
        q->head = q->tail = 0;
        return 0;
    }
    return q->buf[q->head].cycle;
}

static avr_cycle_count_t rx_timer(avr_t *avr, avr_cycle_count_t when, void *param) {
    cosim_t *s = param;
    (void)when;
    queue_t *q = &s->rx;
    fix_uart_byte_time(s);
    while (q->head < q->tail && q->buf[q->head].cycle <= avr->cycle) {
        avr_raise_irq(s->uart_in, q->buf[q->head].value);
        q->head++;
    }
    if (q->head == q->tail) {
        q->head = q->tail = 0;
        return 0;
    }
    return q->buf[q->head].cycle;
}

static avr_cycle_count_t stop_timer(avr_t *avr, avr_cycle_count_t when, void *param) {
    (void)avr;
    (void)when;
    ((cosim_t *)param)->stop = 1;
    return 0;
}

static void tx_notify(struct avr_irq_t *irq, uint32_t value, void *param) {
    cosim_t *s = param;
    (void)irq;
    if (s->n_tx == s->cap_tx) {
        size_t cap = s->cap_tx ? 2 * s->cap_tx : 1024;
        event_t *b = realloc(s->tx, cap * sizeof(event_t));
        if (!b) return;
        s->tx = b;
        s->cap_tx = cap;
    }
    s->tx[s->n_tx].cycle = s->avr->cycle;
    s->tx[s->n_tx].value = (uint8_t)value;
    s->n_tx++;
}

static void schedule(cosim_t *s, queue_t *q, avr_cycle_timer_t timer) {
    /* (re)arm `timer` at the earliest queued cycle */
    if (q->head == q->tail) return;
    uint64_t c = q->buf[q->head].cycle;
    uint64_t now = s->avr->cycle;
    avr_cycle_timer_register(s->avr, c > now ? c - now : 0, timer, s);
}

cosim_t *cosim_open(const char *elf_path, const char *mcu, uint32_t frequency, char *err, int errlen) {
    avr_global_logger_set(logger);
    cosim_t *s = calloc(1, sizeof(cosim_t));
    if (!s) return NULL;
    s->fw = calloc(1, sizeof(elf_firmware_t));
    if (!s->fw || elf_read_firmware(elf_path, s->fw) != 0) {
        snprintf(err, errlen, "cannot read the ELF %s", elf_path);
        goto fail;
    }
    s->avr = avr_make_mcu_by_name(mcu);
    if (!s->avr) {
        snprintf(err, errlen, "simavr has no core %s", mcu);
        goto fail;
    }
    avr_init(s->avr);
    s->avr->log = LOG_WARNING;
    s->avr->frequency = frequency;
    s->avr->sleep = no_sleep;
    avr_load_firmware(s->avr, s->fw);
    s->avr->frequency = frequency;
    uint32_t flags = 0;
    avr_ioctl(s->avr, AVR_IOCTL_UART_SET_FLAGS('0'), &flags);
    for (avr_io_t *io = s->avr->io_port; io; io = io->next) {
        if (strcmp(io->kind, "uart") == 0 && ((avr_uart_t *)io)->name == '0')
            s->uart = (avr_uart_t *)io;
    }
    if (!s->uart) {
        snprintf(err, errlen, "simavr core %s has no USART0", mcu);
        goto fail;
    }
    /* simavr polls a low-level external interrupt input every cycle while the pin is low, in
     * any mode, until the pin goes high: the SC inputs may rest low for seconds. Level
     * triggering then acts as a falling edge (the firmware uses CHANGE). */
    for (int i = 0; i < EXTINT_COUNT; i++)
        avr_extint_set_strict_lvl_trig(s->avr, i, 0);
    patch_timers(s->avr);
    s->uart_in = avr_io_getirq(s->avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_INPUT);
    avr_irq_register_notify(avr_io_getirq(s->avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUTPUT),
                            tx_notify, s);
    return s;
fail:
    if (s->avr) avr_terminate(s->avr);
    free(s->fw);
    free(s);
    return NULL;
}

void cosim_close(cosim_t *s) {
    if (!s) return;
    avr_terminate(s->avr);
    free(s->edges.buf);
    free(s->rx.buf);
    free(s->tx);
    free(s->fw);
    free(s);
}

int cosim_add_output(cosim_t *s, uint16_t port, uint8_t bit, uint16_t tccr, uint8_t com_mask, uint16_t ocr) {
    if (s->n_out == MAX_PINS) return -1;
    out_pin_t *p = &s->out[s->n_out];
    p->port = port;
    p->bit = bit;
    p->tccr = tccr;
    p->com_mask = com_mask;
    p->ocr = ocr;
    return s->n_out++;
}

int cosim_add_input(cosim_t *s, char port, uint8_t bit, uint8_t level) {
    if (s->n_in == MAX_PINS) return -1;
    avr_irq_t *irq = avr_io_getirq(s->avr, AVR_IOCTL_IOPORT_GETIRQ(port), bit);
    if (!irq) return -2;
    s->in_irq[s->n_in] = irq;
    s->in_level[s->n_in] = level ? 1 : 0;
    avr_raise_irq(irq, s->in_level[s->n_in]);
    return s->n_in++;
}

int cosim_queue_edge(cosim_t *s, uint64_t cycle, int input) {
    if (input < 0 || input >= s->n_in) return -1;
    int was_empty = s->edges.head == s->edges.tail;
    if (push(&s->edges, cycle, (uint8_t)input) != 0) return -2;
    if (was_empty) schedule(s, &s->edges, edge_timer);
    return 0;
}

int cosim_queue_rx(cosim_t *s, uint64_t cycle, const uint8_t *bytes, int n, uint32_t byte_cycles) {
    int was_empty = s->rx.head == s->rx.tail;
    for (int i = 0; i < n; i++)
        if (push(&s->rx, cycle + (uint64_t)i * byte_cycles, bytes[i]) != 0) return -2;
    if (was_empty) schedule(s, &s->rx, rx_timer);
    return 0;
}

/* Run until avr->cycle >= until. Returns 0, or the simavr state (cpu_Done, cpu_Crashed) that
 * ended the run early. */
int cosim_run(cosim_t *s, uint64_t until) {
    avr_t *avr = s->avr;
    if (avr->cycle >= until) return 0;
    fix_uart_byte_time(s);
    s->stop = 0;
    avr_cycle_timer_register(avr, until - avr->cycle, stop_timer, s);
    while (!s->stop) {
        int state = avr_run(avr);
        if (state == cpu_Done || state == cpu_Crashed) {
            avr_cycle_timer_cancel(avr, stop_timer, s);
            return state;
        }
        if (avr->cycle >= until) break;
    }
    avr_cycle_timer_cancel(avr, stop_timer, s);
    return 0;
}

/* Run until the program counter reaches `pc` (a byte address, as in the ELF), at most to cycle
 * `max_cycle`. Returns 0 when reached, 1 when not, or the simavr state that ended the run. */
int cosim_run_to_pc(cosim_t *s, uint32_t pc, uint64_t max_cycle) {
    avr_t *avr = s->avr;
    while (avr->pc != pc) {
        if (avr->cycle >= max_cycle) return 1;
        int state = avr_run(avr);
        if (state == cpu_Done || state == cpu_Crashed) return state;
    }
    return 0;
}

uint64_t cosim_outputs(cosim_t *s);

/* Run until the output pins change (checked after every instruction) or the cycle count
 * reaches `until`. Returns 0 (changed or reached: see cosim_cycle), or the simavr state that
 * ended the run. For timing measurements: slower than cosim_run. */
int cosim_run_until_change(cosim_t *s, uint64_t until) {
    avr_t *avr = s->avr;
    uint64_t start = cosim_outputs(s);
    while (avr->cycle < until) {
        int state = avr_run(avr);
        if (state == cpu_Done || state == cpu_Crashed) return state;
        if (cosim_outputs(s) != start) break;
    }
    return 0;
}

uint64_t cosim_cycle(cosim_t *s) { return s->avr->cycle; }

/* One byte per output pin, packed little-endian (pin 0 in the low byte); at most 8 pins. */
uint64_t cosim_outputs(cosim_t *s) {
    uint8_t *d = s->avr->data;
    uint64_t key = 0;
    for (int i = 0; i < s->n_out && i < 8; i++) {
        out_pin_t *p = &s->out[i];
        uint8_t v;
        if (p->tccr && (d[p->tccr] & p->com_mask))
            v = d[p->ocr];
        else
            v = (d[p->port] >> p->bit) & 1 ? 255 : 0;
        key |= (uint64_t)v << (8 * i);
    }
    return key;
}

uint8_t cosim_peek(cosim_t *s, uint16_t addr) { return s->avr->data[addr]; }

int cosim_tx_take(cosim_t *s, uint64_t *cycles, uint8_t *bytes, int max) {
    int n = (int)s->n_tx < max ? (int)s->n_tx : max;
    for (int i = 0; i < n; i++) {
        cycles[i] = s->tx[i].cycle;
        bytes[i] = s->tx[i].value;
    }
    memmove(s->tx, s->tx + n, (s->n_tx - n) * sizeof(event_t));
    s->n_tx -= n;
    return n;
}

int cosim_tx_pending(cosim_t *s) { return (int)s->n_tx; }
