/* motor.h: the Motor class, after the thesis' listing 4.8.
 *
 * Reconstructed: the include guard (the listing's `#ifndef motor.h` has no #define);
 * `accelleration` is spelled `acceleration` as in listing 4.10's definition; freeSpin() is
 * added for a motion of +-1 with speed 0 (§3.2.3: the wheel free-spins, STOP low). */
#ifndef MOTOR_H
#define MOTOR_H
#include "wheel.h"

#define THRESHOLD_CONTROL 4
#define THRESHOLD_SMALL_ACC 0.005
#define THRESHOLD_MEDIUM_ACC 0.009
#define THRESHOLD_HIGH_ACC 0.011
#define DELAY_SMALL_ACC 50
#define DELAY_MEDIUM_ACC 150
#define DELAY_HIGH_ACC 250

class Motor {
public:
  int PIN_STOP;
  int PIN_BREAK;
  int PIN_DIRECTION;
  int PIN_CONTROL;
  int PIN_SPEED;
  int motion = STOP;

  // in RPM
  double referenceSpeed = 0.0;
  double actualSpeed = 0.0;
  double drivenSpeed = 0.0;

  bool sensed = false;
  bool controlled = false;

  Motor(int stops, int breaks, int dirs, int control, int speed);
  void stop();
  void start();
  void freeSpin();
  void forward();
  void backward();
  void changeDirection();
  void drive(double referenceSpeed);
  void driveNoAcc(double drivSpeed);
  void acceleration(double initialSpeed, double finalSpeed);
};

#endif
