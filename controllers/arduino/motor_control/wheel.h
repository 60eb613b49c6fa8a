/* wheel.h: wheel constants and conversions, after the thesis' listing 4.7.
 *
 * Reconstructed: the include guard (the listing prints `#ifndef wheel.h` / `#define Morse_h`,
 * which does not guard anything); the definitions in wheel.cpp of the functions the listing
 * only declares. */
#ifndef WHEEL_H
#define WHEEL_H
#include "math.h"
#include "Arduino.h"

#define MAX_VEL 1054      // (RPM) evaluated considering that 0,38 Amp --> 71,5 RPM. Max amps are 250/36 = 6,944
#define WHEEL_DIAM 0.25
#define THRESHOLD 0.01
#define R 0.24            // distance between the center of the wheel and the middle point of the robot
#define L 0.48            // distance between the center of the two wheels
#define FORWARD 1
#define BACKWARD -1
#define STOP 0

double computeDuty(double speed);        // duty cycle from a speed in m/s
double computeDutyFromRPM(double rpm);
double computeRPM(double speed);
double computeVolt(double refDuty);      // analogWrite value from a duty cycle
double computeReal(double speed, String direction);  // declared by the listing; not printed, not used
double computeSpeedFromSignal(double val);
double computeSpeedFromRPM(double rpm);

#endif
