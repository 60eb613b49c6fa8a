/* wheel.cpp: listing 4.9 (computeDutyFromRPM, computeVolt) and the conversions listing 4.7
 * declares without printing them (reconstructed, marked below). computeReal is neither printed
 * nor called, so it is not defined. */
#include "wheel.h"

double computeDutyFromRPM(double rpm)
{
  return rpm / MAX_VEL;
}

double computeVolt(double refDuty)
{
  return refDuty * 255;  // duty = 1 corresponds to 5 V, which is analogWrite 255
}

/* Reconstructed: RPM of a wheel of diameter WHEEL_DIAM rolling at `speed` m/s. */
double computeRPM(double speed)
{
  return speed * 60.0 / (PI * WHEEL_DIAM);
}

/* Reconstructed: the inverse of computeRPM. */
double computeSpeedFromRPM(double rpm)
{
  return rpm * PI * WHEEL_DIAM / 60.0;
}

/* Reconstructed: computeDutyFromRPM of computeRPM. */
double computeDuty(double speed)
{
  return computeDutyFromRPM(computeRPM(speed));
}

/* Reconstructed: `val` is the micros() elapsed over one sample of 90 SC changes, i.e. one
 * wheel revolution (§3.2.3), so the speed is 60e6 / val RPM. A non-positive span gives 0. */
double computeSpeedFromSignal(double val)
{
  if (val <= 0) return 0;
  return 60000000.0 / val;
}
