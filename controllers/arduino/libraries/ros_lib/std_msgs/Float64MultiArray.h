/* std_msgs/Float64MultiArray (amr-twin's own code).
 *
 * Wire layout (ROS 1): layout.dim (uint32 count, then per dimension: string label, uint32 size,
 * uint32 stride), layout.data_offset (uint32), data (uint32 count, then float64 values).
 * Kept on the board: data_offset and up to CAPACITY values (data_length is clipped to
 * CAPACITY; the wire's further values and the dimensions are skipped). */
#ifndef AMR_TWIN_STD_MSGS_FLOAT64MULTIARRAY_H
#define AMR_TWIN_STD_MSGS_FLOAT64MULTIARRAY_H

#include "ros/msg.h"

namespace std_msgs {

class Float64MultiArray : public ros::Msg {
public:
  enum { CAPACITY = 8 };
  uint32_t data_offset;
  uint32_t data_length;
  double data[CAPACITY];

  Float64MultiArray() : data_offset(0), data_length(0) {
    for (int i = 0; i < CAPACITY; i++) data[i] = 0;
  }

  virtual int serializedLength() const { return 12 + 8 * (int)data_length; }
  virtual int serialize(unsigned char *out) const {
    int o = writeUint32(out, 0);                  /* no dimensions */
    o += writeUint32(out + o, data_offset);
    o += writeUint32(out + o, data_length);
    for (uint32_t i = 0; i < data_length; i++) o += serializeAvrFloat64(out + o, data[i]);
    return o;
  }

  virtual int deserialize(unsigned char *in) {
    int o = 0;
    uint32_t n_dim = readUint32(in + o);
    o += 4;
    for (uint32_t d = 0; d < n_dim; d++) {
      o += 4 + readUint32(in + o);                /* label */
      o += 8;                                     /* size, stride */
    }
    data_offset = readUint32(in + o);
    o += 4;
    uint32_t n = readUint32(in + o);
    o += 4;
    data_length = n < CAPACITY ? n : CAPACITY;
    for (uint32_t i = 0; i < n; i++) {
      float f;
      deserializeAvrFloat64(in + o, &f);
      if (i < CAPACITY) data[i] = f;
      o += 8;
    }
    return o;
  }

  virtual const char *getType() { return "std_msgs/Float64MultiArray"; }
  virtual const char *getMD5() { return "4b7d974086d4060e7db4613a7e6c3ba4"; }
};

}  // namespace std_msgs

#endif
