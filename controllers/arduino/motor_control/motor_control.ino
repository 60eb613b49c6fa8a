/* motor_control.ino: the thesis' Arduino Mega firmware (§3.2.3, listings 4.7-4.12), reconstructed
 * for the amr-twin, where it is compiled with avr-gcc and run on an emulated ATmega2560
 * (`amr-twin run ... --firmware avr`).
 *
 * Printed in the thesis and followed here: PI_Control (listing 4.11), speedChangeInt0/1 and
 * speedChangeInt (listing 4.12), the Motor class (listings 4.8, 4.10), the conversions (4.9).
 * Reconstructed (not printed; the same choices as controllers/faithful.py, see docs/explanation/firmware.md):
 * the pins, the declarations and initial values of the globals, min_control/max_control, T,
 * the wheel_Command callback, PICallBack, setup() and loop(). */
#include <ros.h>
#include <std_msgs/Float64.h>
#include <std_msgs/Float64MultiArray.h>
#include <TimerOne.h>
#include "wheel.h"
#include "motor.h"

/* Reconstructed pins: SC on 2 and 3 (§3.2.3); the others are the twin's wiring (BoardParams).
 * Motor(STOP, BRAKE, DIR, PWM, SC) */
Motor motors[2] = {Motor(22, 24, 26, 6, 2), Motor(23, 25, 27, 7, 3)};

/* PI gains (text after listing 4.11); kd is unused (0). T = 0.2 s, the timer period, is not
 * printed; min_control and max_control are not printed either (0 and MAX_VEL RPM). */
double kp = 0.001;
double ki = 0.15;
double kd = 0;
double T = 0.2;
double min_control = 0;
double max_control = MAX_VEL;

unsigned long last_time[2] = {0, 0};
double last_error[2] = {0, 0};
double total_error[2] = {0, 0};
double previousSetPoint[2] = {0, 0};

volatile int counter[2] = {0, 0};
volatile unsigned long lastRead[2] = {0, 0};
volatile unsigned long actualRead[2] = {0, 0};
volatile bool reader[2] = {false, false};

ros::NodeHandle node;
std_msgs::Float64 toPub_vel[2];
ros::Publisher publisher[2] = {ros::Publisher("wheel0_Vel", &toPub_vel[0]),
                               ros::Publisher("wheel1_Vel", &toPub_vel[1])};

void wheelCommandCallback(const std_msgs::Float64MultiArray &msg);
ros::Subscriber<std_msgs::Float64MultiArray> subscriber("wheel_Command", &wheelCommandCallback);

void speedChangeInt(int index);
void speedChangeInt0();
void speedChangeInt1();

/* Reconstructed: wheel_Command = [motionL, speedL, motionR, speedR] (RPM). Motion 0 brakes the
 * wheel; motion +-1 with speed 0 lets it free-spin (the PI leaves it alone: setPoint 0);
 * otherwise drive() ramps to the speed. Left wheel first: its ramp's delay()s block loop(). */
void wheelCommandCallback(const std_msgs::Float64MultiArray &msg)
{
  if (msg.data_length < 4)
    return;
  for (int i = 0; i < 2; i++)
  {
    int motion = (int)msg.data[2 * i];
    double speed = msg.data[2 * i + 1];
    motors[i].motion = motion;
    if (motion == STOP)
    {
      motors[i].referenceSpeed = 0.0;
      motors[i].stop();
    }
    else if (speed == 0)
    {
      motors[i].referenceSpeed = 0.0;
      motors[i].freeSpin();
    }
    else
    {
      motors[i].referenceSpeed = speed;
      motors[i].drive(speed);
    }
  }
}

void PI_Control(double setPoint, double sensedOutput, int index)
{
  noInterrupts();
  motors[index].sensed = false;
  if (setPoint != 0)
  {
    unsigned long current_time = millis();  // milliseconds since the Arduino started
    int delta_time = current_time - last_time[index];

    if (delta_time >= T)
    {
      if (setPoint != previousSetPoint[index])
      {
        total_error[index] = 0;
        previousSetPoint[index] = setPoint;
      }

      double error = setPoint - sensedOutput;

      if (abs(error) <= THRESHOLD_CONTROL)
        return;  // as printed: returns without interrupts() (docs/explanation/firmware.md, quirks)

      total_error[index] += error;  // integral term
      if (total_error[index] >= max_control) total_error[index] = max_control;
      else if (total_error[index] <= min_control) total_error[index] = min_control;

      double delta_error = error - last_error[index];  // derivative term
      double bias = setPoint / 10;
      double controlSpeed = setPoint + (kp * error + (ki * T) * total_error[index] + (kd / T) * delta_error) - bias;

      if (controlSpeed >= max_control) controlSpeed = max_control;
      else if (controlSpeed <= min_control) controlSpeed = min_control;

      last_error[index] = error;
      last_time[index] = current_time;
      motors[index].driveNoAcc(controlSpeed);
    }
    motors[index].controlled = true;
    interrupts();
  }
}

/* Reconstructed (§3.2.3): every 0.2 s, attach the SC interrupt of a wheel whose speed has not
 * been sensed yet; for a sensed wheel not yet controlled, run the PI. Runs in the Timer1 ISR. */
void PICallBack()
{
  for (int i = 0; i < 2; i++)
  {
    if (!motors[i].sensed)
      attachInterrupt(digitalPinToInterrupt(motors[i].PIN_SPEED), i == 0 ? speedChangeInt0 : speedChangeInt1, CHANGE);
    else if (!motors[i].controlled)
      PI_Control(motors[i].referenceSpeed, motors[i].actualSpeed, i);
  }
}

void speedChangeInt0()
{
  speedChangeInt(0);
}

void speedChangeInt1()
{
  speedChangeInt(1);
}

void speedChangeInt(int index)
{
  if (!motors[index].sensed)
  {
    if (counter[index] == 0)
    {
      lastRead[index] = micros();
      counter[index]++;
      reader[index] = true;
    }
    else if (counter[index] == 90)
    {
      detachInterrupt(digitalPinToInterrupt(motors[index].PIN_SPEED));
      noInterrupts();
      actualRead[index] = micros() - lastRead[index];
      lastRead[index] = micros();

      double a = actualRead[index];
      motors[index].actualSpeed = computeSpeedFromSignal(a);
      toPub_vel[index].data = motors[index].actualSpeed;  // speed value to publish on the ROS topic
      publisher[index].publish(&toPub_vel[index]);
      node.spinOnce();

      counter[index] = 0;
      reader[index] = false;
      motors[index].sensed = true;
      motors[index].controlled = false;
      interrupts();
    }
    else
    {
      counter[index]++;
    }
  }
}

/* Reconstructed: rosserial at 115200 baud (launch file, listing 4.1); wheels braked, drivers
 * enabled, DIR forward; Timer1 every 0.2 s calling PICallBack (§3.2.3). */
void setup()
{
  node.getHardware()->setBaud(115200);
  node.initNode();
  node.advertise(publisher[0]);
  node.advertise(publisher[1]);
  node.subscribe(subscriber);
  for (int i = 0; i < 2; i++)
  {
    motors[i].stop();
    digitalWrite(motors[i].PIN_STOP, HIGH);
    motors[i].forward();
  }
  Timer1.initialize(200000);
  Timer1.attachInterrupt(PICallBack);
}

/* Reconstructed: serve rosserial; wheel_Command callbacks run from here. */
void loop()
{
  node.spinOnce();
}
