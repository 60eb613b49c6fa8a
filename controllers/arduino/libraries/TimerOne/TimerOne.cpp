/* TimerOne.cpp: see TimerOne.h (amr-twin's own code). */
#include "TimerOne.h"

TimerOne Timer1;
void (*TimerOne::isrCallback)() = 0;

ISR(TIMER1_COMPA_vect) {
  if (TimerOne::isrCallback) TimerOne::isrCallback();
}

void TimerOne::initialize(unsigned long microseconds) {
  TCCR1A = 0;                      /* no compare outputs; CTC: WGM12 with TOP = OCR1A */
  TCCR1B = _BV(WGM12);             /* stopped until setPeriod() selects a clock */
  setPeriod(microseconds);
}

void TimerOne::setPeriod(unsigned long microseconds) {
  /* ticks of the 16-bit counter at each prescaler; the smallest prescaler that fits wins */
  const unsigned long cycles = (F_CPU / 1000000UL) * microseconds;
  static const uint16_t prescale[] = {1, 8, 64, 256, 1024};
  static const uint8_t select[] = {_BV(CS10), _BV(CS11), _BV(CS11) | _BV(CS10), _BV(CS12),
                                   _BV(CS12) | _BV(CS10)};
  uint8_t k = 0;
  while (k < 4 && cycles / prescale[k] > 65536UL) k++;
  unsigned long ticks = cycles / prescale[k];
  if (ticks > 65536UL) ticks = 65536UL;
  clockSelectBits = select[k];
  uint8_t oldSREG = SREG;
  cli();
  OCR1A = (uint16_t)(ticks - 1);
  TCNT1 = 0;
  SREG = oldSREG;
  TCCR1B = _BV(WGM12) | clockSelectBits;
}

void TimerOne::attachInterrupt(void (*isr)()) {
  isrCallback = isr;
  TIFR1 = _BV(OCF1A);
  TIMSK1 |= _BV(OCIE1A);
}

void TimerOne::attachInterrupt(void (*isr)(), unsigned long microseconds) {
  setPeriod(microseconds);
  attachInterrupt(isr);
}

void TimerOne::detachInterrupt() { TIMSK1 &= ~_BV(OCIE1A); }

void TimerOne::start() {
  TCCR1B = _BV(WGM12);
  TCNT1 = 0;
  TIFR1 = _BV(OCF1A);
  TCCR1B = _BV(WGM12) | clockSelectBits;
}

void TimerOne::stop() { TCCR1B = _BV(WGM12); }
