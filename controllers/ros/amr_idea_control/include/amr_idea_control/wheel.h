/* wheel.h of the high-level controller: reconstructs the thesis' listing 4.2 (its constants and the two
 * conversion functions). Reconstructed (not printed): the include guard (the listing's `#ifndef wheel.h`
 * is not a valid macro name), PI (the listings use it; math.h's M_PI), MIN_RPM and MAX_RPM of the
 * client's range check (§3.2.2 names them without values: 0 and MAX_VEL, as amr_twin's
 * controllers/wheel_command.py decides), checkSpeed. */
#ifndef AMR_IDEA_CONTROL_WHEEL_H
#define AMR_IDEA_CONTROL_WHEEL_H

#include <math.h>

#define MAX_VEL 1054  // (RPM) evaluated considering that 0,38 Amp --> 71,5 RPM. Max amps are 250/36 = 6,944
#define WHEEL_DIAM 0.25
#define THRESHOLD 0.01
#define R 0.24  // distance between the center of the wheel and the middle point of the robot
#define L 0.48  // distance between the center of the two wheels
#define FORWARD 1
#define BACKWARD -1
#define STOP 0

#define PI M_PI
#define MIN_RPM 0.0
#define MAX_RPM ((double)MAX_VEL)

/* m/s of the wheel's rim -> RPM */
double computeRPM(double speed);

/* deg/s -> rad/s */
double computeRadFromDeg(double vel);

/* 1 if MIN_RPM <= |rpm| <= MAX_RPM, else 0 (listing 4.4 calls it on the signed rpm; backward commands
 * are accepted in fig. 3.4, so the magnitude is checked) */
int checkSpeed(double rpm);

#endif
