/* ArduinoHardware.h: the serial port and clock the NodeHandle uses (amr-twin's own code).
 * As rosserial_arduino's: Serial (USART0, the Mega's USB port), 57600 baud unless setBaud()
 * is called before initNode().
 *
 * idle(): called by spinOnce() when it found nothing to read. Unless AMR_TWIN_ROS_BUSY_SPIN is
 * defined it puts the CPU in idle sleep until the next interrupt (the timer0 tick of millis()
 * at the latest, every 1.024 ms; a received byte; an SC edge; Timer1). Only in main context
 * with interrupts enabled, and with the check for a byte and the sleep made atomic (SEI;SLEEP),
 * so a byte that arrives in between is not left waiting. For a loop() that only calls
 * spinOnce(), as the thesis', nothing observable changes; the emulator skips the idle cycles. */
#ifndef AMR_TWIN_ARDUINO_HARDWARE_H
#define AMR_TWIN_ARDUINO_HARDWARE_H

#include <Arduino.h>
#include <avr/sleep.h>

class ArduinoHardware {
public:
  ArduinoHardware() : baud_(57600) {}
  void setBaud(long baud) { baud_ = baud; }
  long getBaud() { return baud_; }
  void init() { Serial.begin(baud_); }
  int read() { return Serial.read(); }
  void write(uint8_t *data, int length) { Serial.write(data, length); }
  unsigned long time() { return millis(); }

  void idle() {
#ifndef AMR_TWIN_ROS_BUSY_SPIN
    uint8_t sreg = SREG;
    if (!(sreg & _BV(SREG_I))) return;  /* inside an ISR or a critical section: never sleep */
    cli();
    if (Serial.available() == 0) {
      set_sleep_mode(SLEEP_MODE_IDLE);
      sleep_enable();
      sei();
      sleep_cpu();
      sleep_disable();
    }
    SREG = sreg;
#endif
  }

private:
  long baud_;
};

#endif
