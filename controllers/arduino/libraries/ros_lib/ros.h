/* ros.h: the amr-twin's minimal rosserial client for the Arduino Mega (the project's own code).
 *
 * The same API as rosserial_arduino's ros_lib for what the thesis sketch uses:
 * ros::NodeHandle (initNode, advertise, subscribe, spinOnce, getHardware()->setBaud),
 * ros::Publisher, ros::Subscriber<MsgT>, std_msgs::Float64, std_msgs::Float64MultiArray.
 * Frames follow the rosserial serial protocol (protocol version 0xfe, length and message
 * checksums); the twin's PC side (amr_twin/rosserial_frame.py) speaks the same protocol.
 *
 * Differences from rosserial_arduino, all documented in docs/firmware.md:
 * - no time synchronisation, parameters, logging or services;
 * - publish() sends at once, without waiting for serial_node's topic negotiation (it still
 *   answers a topic request with the TopicInfo frames, as rosserial does);
 * - Float64MultiArray keeps at most 8 data values and no layout dimensions.
 */
#ifndef AMR_TWIN_ROS_H
#define AMR_TWIN_ROS_H

#include "ros/node_handle.h"
#include "ArduinoHardware.h"

namespace ros {
/* rosserial_arduino's sizes for the ATmega2560: 25 subscribers, 25 publishers, 512-byte buffers. */
typedef NodeHandle_<ArduinoHardware, 25, 25, 512, 512> NodeHandle;
}

#endif
