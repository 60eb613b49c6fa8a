/* TimerOne.h: a periodic Timer1 interrupt with the API of PJRC's TimerOne library (amr-twin's
 * own code; the thesis' setup() calls Timer1.initialize(200000) and Timer1.attachInterrupt).
 *
 * Reconstruction: PJRC's library counts in phase-and-frequency-correct PWM mode and interrupts
 * on overflow; this one uses CTC mode on OCR1A with the OCR1A compare interrupt. Same period,
 * and the first interrupt comes one period after initialize(), as with PJRC's. No PWM outputs. */
#ifndef AMR_TWIN_TIMERONE_H
#define AMR_TWIN_TIMERONE_H

#include <Arduino.h>

class TimerOne {
public:
  void initialize(unsigned long microseconds = 1000000);
  void setPeriod(unsigned long microseconds);
  void attachInterrupt(void (*isr)());
  void attachInterrupt(void (*isr)(), unsigned long microseconds);
  void detachInterrupt();
  void start();
  void stop();

  static void (*isrCallback)();

private:
  uint8_t clockSelectBits;
};

extern TimerOne Timer1;

#endif
