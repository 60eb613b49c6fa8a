/* wheel_Command_Client.cpp: reconstructs the thesis' wheel_Command_Client (§3.2.2, fig. 3.2, listings
 * 4.4-4.6). linear() is listing 4.4, angular() listing 4.5 (its motion codes as printed: both FORWARD when
 * |icc| >= R), stop() listing 4.6, each returning 0 (done), 1 (a speed outside MIN_RPM..MAX_RPM) or -1 (the
 * service call failed). Reconstructed (not printed): the globals client and srv the listings use, motor()
 * (fig. 3.6: the chosen wheel at its sense and speed, the other free-spinning with motion 1 and speed 0),
 * the menu's wording and main() (fig. 3.2 shows a terminal menu: linear motion, rotation about an ICC,
 * stop, motor motion; its text is not printed), PI from math.h (wheel.h), and fabs for the listings' abs of a float. */
#include <iostream>
#include <string>

#include "ros/ros.h"
#include "amr_idea_control/RequestPacket.h"
#include "amr_idea_control/wheel.h"

ros::ServiceClient client;
amr_idea_control::RequestPacket srv;

int linear(float speed)
{
  ros::NodeHandle n;
  float rpm = speed * 60.0 / (WHEEL_DIAM * PI);
  if (checkSpeed(rpm))
  {
    int motion;
    if (rpm >= 0)
      motion = FORWARD;
    else
      motion = BACKWARD;
    rpm = fabs(rpm);
    client = n.serviceClient<amr_idea_control::RequestPacket>("wheel_Command_Service");
    srv.request.motionL = motion;
    srv.request.motionR = motion;
    srv.request.speedL = rpm;
    srv.request.speedR = rpm;
    if (!client.call(srv))
    {
      ROS_ERROR("ERROR while linear motion");
      return -1;
    }
  }
  else
  {
    ROS_ERROR("ERROR: linear velocity not valid");
    return 1;
  }
  return 0;
}

int angular(float speed, float icc)
{
  ros::NodeHandle n;
  float radSpeed = speed * PI / 180.0;
  float vel[2];
  vel[0] = radSpeed * (icc - R) * 60.0 / (WHEEL_DIAM * PI);
  vel[1] = radSpeed * (icc + R) * 60.0 / (WHEEL_DIAM * PI);
  client = n.serviceClient<amr_idea_control::RequestPacket>("wheel_Command_Service");
  if (fabs(icc) < R)
  {
    srv.request.motionL = vel[0] > 0 ? FORWARD : BACKWARD;
    srv.request.motionR = vel[1] > 0 ? FORWARD : BACKWARD;
  }
  else
  {
    srv.request.motionL = FORWARD;
    srv.request.motionR = FORWARD;
  }
  vel[0] = fabs(vel[0]);
  vel[1] = fabs(vel[1]);
  if (checkSpeed(vel[0]) == 0)
  {
    ROS_ERROR("ERROR: angular velocity not valid");
    return 1;
  }
  srv.request.speedL = vel[0];
  if (checkSpeed(vel[1]) == 0)
  {
    ROS_ERROR("ERROR: angular velocity not valid");
    return 1;
  }
  srv.request.speedR = vel[1];
  if (!client.call(srv))
  {
    ROS_ERROR("ERROR while angular motion");
    return -1;
  }
  return 0;
}

int stop()
{
  ros::NodeHandle n;
  client = n.serviceClient<amr_idea_control::RequestPacket>("wheel_Command_Service");
  srv.request.motionL = 0;
  srv.request.motionR = 0;
  srv.request.speedL = 0;
  srv.request.speedR = 0;
  if (!client.call(srv))
  {
    ROS_ERROR("ERROR while stop motion");
    return -1;
  }
  return 0;
}

int motor(int index, int sense, float speed)
{
  ros::NodeHandle n;
  float rpm = computeRPM(speed);
  if ((index != 0 && index != 1) || (sense != FORWARD && sense != BACKWARD) || speed < 0 || !checkSpeed(rpm))
  {
    ROS_ERROR("ERROR: motor velocity not valid");
    return 1;
  }
  client = n.serviceClient<amr_idea_control::RequestPacket>("wheel_Command_Service");
  srv.request.motionL = index == 0 ? sense : FORWARD;
  srv.request.speedL = index == 0 ? rpm : 0;
  srv.request.motionR = index == 1 ? sense : FORWARD;
  srv.request.speedR = index == 1 ? rpm : 0;
  if (!client.call(srv))
  {
    ROS_ERROR("ERROR while motor motion");
    return -1;
  }
  return 0;
}

static bool ask(const char *prompt, float &value)
{
  std::cout << prompt << std::flush;
  std::string text;
  if (!(std::cin >> text)) return false;
  try
  {
    value = std::stof(text);
  }
  catch (...)
  {
    std::cout << "not a number: " << text << std::endl;
    return false;
  }
  return true;
}

int main(int argc, char **argv)
{
  ros::init(argc, argv, "wheel_Command_Client");
  ros::NodeHandle n;
  while (ros::ok())
  {
    std::cout << "\nwheel_Command_Client\n"
              << "  1) Linear motion          (speed, m/s; negative: backward)\n"
              << "  2) Rotation about an ICC  (speed, deg/s; ICC distance, m)\n"
              << "  3) Stop                   (brake both wheels)\n"
              << "  4) Motor motion           (motor 0 left / 1 right; sense 1 / -1; speed, m/s)\n"
              << "  0) Exit\n"
              << "choice: " << std::flush;
    std::string choice;
    if (!(std::cin >> choice) || choice == "0") break;
    int code;
    float a, b, c;
    if (choice == "1" && ask("linear speed [m/s]: ", a))
      code = linear(a);
    else if (choice == "2" && ask("angular speed [deg/s]: ", a) && ask("ICC distance [m]: ", b))
      code = angular(a, b);
    else if (choice == "3")
      code = stop();
    else if (choice == "4" && ask("motor (0 left, 1 right): ", a) && ask("sense (1 forward, -1 backward): ", b) &&
             ask("speed [m/s]: ", c))
      code = motor((int)a, (int)b, c);
    else
    {
      std::cout << "unknown choice or value" << std::endl;
      continue;
    }
    std::cout << "request [" << srv.request.motionL << ", " << srv.request.speedL << ", " << srv.request.motionR
              << ", " << srv.request.speedR << "] (code " << code << ")" << std::endl;
  }
  return 0;
}
