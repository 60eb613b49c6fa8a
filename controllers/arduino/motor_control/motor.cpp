/* motor.cpp: drive, driveNoAcc and acceleration after the thesis' listing 4.10; the other
 * methods are not printed and are reconstructed (docs/explanation/firmware.md, "Reconstruction choices"). */
#include "motor.h"

/* Reconstructed: keep the pins, make the driver pins outputs and the SC pin an input. */
Motor::Motor(int stops, int breaks, int dirs, int control, int speed)
{
  PIN_STOP = stops;
  PIN_BREAK = breaks;
  PIN_DIRECTION = dirs;
  PIN_CONTROL = control;
  PIN_SPEED = speed;
  pinMode(PIN_STOP, OUTPUT);
  pinMode(PIN_BREAK, OUTPUT);
  pinMode(PIN_DIRECTION, OUTPUT);
  pinMode(PIN_CONTROL, OUTPUT);
  pinMode(PIN_SPEED, INPUT);
}

/* Reconstructed: motion STOP holds the wheel: PWM 0, BRAKE high (§3.2). */
void Motor::stop()
{
  analogWrite(PIN_CONTROL, 0);
  digitalWrite(PIN_BREAK, HIGH);
}

/* Reconstructed: release the brake and enable the driver (STOP is active low). */
void Motor::start()
{
  digitalWrite(PIN_BREAK, LOW);
  digitalWrite(PIN_STOP, HIGH);
}

/* Reconstructed: motion +-1 at speed 0: PWM 0, BRAKE low, STOP low, the wheel coasts. */
void Motor::freeSpin()
{
  analogWrite(PIN_CONTROL, 0);
  digitalWrite(PIN_BREAK, LOW);
  digitalWrite(PIN_STOP, LOW);
}

/* Reconstructed: DIR high turns the wheel so that the robot moves forward (amr_twin/pins.py). */
void Motor::forward()
{
  digitalWrite(PIN_DIRECTION, HIGH);
}

void Motor::backward()
{
  digitalWrite(PIN_DIRECTION, LOW);
}

/* Reconstructed: invert the motion and the DIR pin. */
void Motor::changeDirection()
{
  motion = -motion;
  if (motion == FORWARD)
    forward();
  else
    backward();
}

void Motor::drive(double drivSpeed)
{
  Motor::start();
  if (motion == FORWARD)
  {
    forward();
  }
  else if (motion == BACKWARD)
  {
    backward();
  }
  else
    return;
  drivenSpeed = drivSpeed;
  Motor::acceleration(actualSpeed, drivenSpeed);
}

void Motor::driveNoAcc(double drivSpeed)
{
  drivenSpeed = drivSpeed;
  double finalDuty = computeDutyFromRPM(drivSpeed);
  analogWrite(PIN_CONTROL, computeVolt(finalDuty));
}

void Motor::acceleration(double initialSpeed, double finalSpeed)
{
  double initialDuty = computeDutyFromRPM(initialSpeed);
  double finalDuty = computeDutyFromRPM(finalSpeed);
  double deltaDuty = (finalDuty - initialDuty) / 10;

  int delayTime;  // as printed: set only when |deltaDuty| passes a threshold, used only then

  if (abs(deltaDuty) >= THRESHOLD_HIGH_ACC)
    delayTime = DELAY_HIGH_ACC;
  else if (abs(deltaDuty) >= THRESHOLD_MEDIUM_ACC)
    delayTime = DELAY_MEDIUM_ACC;
  else if (abs(deltaDuty) >= THRESHOLD_SMALL_ACC)
    delayTime = DELAY_SMALL_ACC;

  if (deltaDuty >= THRESHOLD_SMALL_ACC)  // signed: a deceleration jumps (docs/explanation/firmware.md)
  {
    for (int i = 1; i <= 10; i++)
    {
      analogWrite(PIN_CONTROL, computeVolt(initialDuty + deltaDuty * i));
      delay(delayTime);
    }
  }
  else
    Motor::driveNoAcc(finalSpeed);
}
