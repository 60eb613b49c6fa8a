/* ros/time.h: ros::Time, and its message std_msgs/Time as rosserial's time sync carries it on
 * topic id 10 (amr-twin's own code): uint32 sec, uint32 nsec, 8 bytes little-endian. */
#ifndef AMR_TWIN_ROS_TIME_H
#define AMR_TWIN_ROS_TIME_H

#include "ros/msg.h"

namespace ros {

class Time : public Msg {
public:
  uint32_t sec;
  uint32_t nsec;

  Time() : sec(0), nsec(0) {}

  void normalize() {
    while (nsec >= 1000000000UL) {
      nsec -= 1000000000UL;
      sec++;
    }
  }

  virtual int serializedLength() const { return 8; }
  virtual int serialize(unsigned char *out) const {
    writeUint32(out, sec);
    writeUint32(out + 4, nsec);
    return 8;
  }
  virtual int deserialize(unsigned char *in) {
    sec = readUint32(in);
    nsec = readUint32(in + 4);
    return 8;
  }
  virtual const char *getType() { return "std_msgs/Time"; }
  virtual const char *getMD5() { return "cd7166c74c552c311fbcc2fe5a7bc289"; }
};

}  // namespace ros

#endif
