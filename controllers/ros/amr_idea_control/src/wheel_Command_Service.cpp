/* wheel_Command_Service.cpp: reconstructs the thesis' listing 4.3 (§4.2.1). sendCommand publishes
 * wheel_Command = [motionL, speedL, motionR, speedR] (std_msgs/Float64MultiArray, queue 100);
 * requestCommand is the service wheel_Command_Service (amr_idea_control/RequestPacket). As printed,
 * apart from the includes the listing does not need (iostream, sstream). */
#include "ros/ros.h"
#include "std_msgs/Float64MultiArray.h"
#include "amr_idea_control/RequestPacket.h"

ros::Publisher publisher;

void sendCommand(int motionL, float speedL, int motionR, float speedR)
{
  std_msgs::Float64MultiArray msg;
  msg.data.resize(4);
  msg.data[0] = motionL;
  msg.data[1] = speedL;
  msg.data[2] = motionR;
  msg.data[3] = speedR;
  publisher.publish(msg);
  ros::spinOnce();
  ROS_INFO("Data sent");
}

bool requestCommand(amr_idea_control::RequestPacket::Request &req, amr_idea_control::RequestPacket::Response &res)
{
  sendCommand(req.motionL, req.speedL, req.motionR, req.speedR);
  return true;
}

int main(int argc, char **argv)
{
  ros::init(argc, argv, "wheel_Command_Service");
  ros::NodeHandle n;
  publisher = n.advertise<std_msgs::Float64MultiArray>("wheel_Command", 100);
  ros::ServiceServer service = n.advertiseService("wheel_Command_Service", requestCommand);
  ROS_INFO("wheel_Command_Service is running");
  ros::spin();
  return 0;
}
