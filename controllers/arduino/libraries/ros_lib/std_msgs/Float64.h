/* std_msgs/Float64 (amr-twin's own code): `float64 data`, 8 bytes on the wire, a 32-bit
 * double on the AVR. */
#ifndef AMR_TWIN_STD_MSGS_FLOAT64_H
#define AMR_TWIN_STD_MSGS_FLOAT64_H

#include "ros/msg.h"

namespace std_msgs {

class Float64 : public ros::Msg {
public:
  double data;

  Float64() : data(0) {}

  virtual int serializedLength() const { return 8; }
  virtual int serialize(unsigned char *out) const { return serializeAvrFloat64(out, data); }

  virtual int deserialize(unsigned char *in) {
    float f;
    int n = deserializeAvrFloat64(in, &f);
    data = f;
    return n;
  }

  virtual const char *getType() { return "std_msgs/Float64"; }
  virtual const char *getMD5() { return "fdb28210bfa9d7c91146260178d9a584"; }
};

}  // namespace std_msgs

#endif
