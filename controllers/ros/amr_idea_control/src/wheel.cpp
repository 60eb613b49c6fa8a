/* wheel.cpp of the high-level controller: the functions listing 4.2 declares, reconstructed (their bodies
 * are not printed; the conversions are those of listings 4.4-4.5 and §2.1.3). */
#include "amr_idea_control/wheel.h"

double computeRPM(double speed)
{
  return speed * 60.0 / (WHEEL_DIAM * PI);
}

double computeRadFromDeg(double vel)
{
  return vel * PI / 180.0;
}

int checkSpeed(double rpm)
{
  double magnitude = fabs(rpm);
  return magnitude >= MIN_RPM && magnitude <= MAX_RPM ? 1 : 0;
}
