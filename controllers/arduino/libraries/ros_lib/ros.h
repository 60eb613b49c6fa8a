/* ros.h: the amr-twin's minimal rosserial client for the Arduino Mega (the project's own code).
 *
 * The same API as rosserial_arduino's ros_lib for what the thesis sketch uses:
 * ros::NodeHandle (initNode, advertise, subscribe, spinOnce, now, getHardware()->setBaud),
 * ros::Publisher, ros::Subscriber<MsgT>, std_msgs::Float64, std_msgs::Float64MultiArray.
 * Frames follow the rosserial serial protocol (protocol version 0xfe, length and message
 * checksums, topic negotiation, time sync, TX_STOP: ros/node_handle.h says what a host relies on);
 * the twin's PC side (amr_twin/ros/rosserial_frame.py) and its rosserial host
 * (amr_twin/ros1/serial_host.py) speak the same protocol.
 *
 * Differences from rosserial_arduino, all documented in docs/explanation/firmware.md:
 * - no parameters, logging or services;
 * - a publish() inside an interrupt is written later, from main context; spinOnce() inside an
 *   interrupt does nothing (ros/node_handle.h);
 * - Float64MultiArray keeps at most 8 data values and no layout dimensions.
 *
 * yield(), which Arduino's delay() calls while it waits, is defined here (weak: a sketch's own
 * wins) to write the frames published inside interrupts meanwhile. */
#ifndef AMR_TWIN_ROS_H
#define AMR_TWIN_ROS_H

#include "ros/node_handle.h"
#include "ArduinoHardware.h"

namespace ros {
/* rosserial_arduino's sizes for the ATmega2560: 25 subscribers, 25 publishers, 512-byte buffers. */
typedef NodeHandle_<ArduinoHardware, 25, 25, 512, 512> NodeHandle;
}

__attribute__((weak)) void yield(void) {
  ros::NodeHandleBase_ *nh = ros::activeNodeHandle();
  if (nh) nh->flushDeferred();
}

#endif
