/* ros/msg.h: base class of the messages and the AVR float64 wire conversions (amr-twin's own code).
 *
 * On the AVR `double` is a 32-bit float, while ROS float64 fields are 8 bytes on the wire:
 * serializeAvrFloat64 widens a float to an IEEE 754 double (exact), deserializeAvrFloat64
 * narrows a double to a float by truncating the mantissa (as rosserial_arduino does);
 * out-of-range magnitudes become infinity or zero. The AVR is little-endian like the wire, so
 * words are copied with memcpy (no variable shifts, which the AVR does bit by bit). */
#ifndef AMR_TWIN_ROS_MSG_H
#define AMR_TWIN_ROS_MSG_H

#include <stdint.h>
#include <string.h>

namespace ros {

class Msg {
public:
  virtual int serializedLength() const = 0;
  virtual int serialize(unsigned char *outbuffer) const = 0;
  virtual int deserialize(unsigned char *inbuffer) = 0;
  virtual const char *getType() = 0;
  virtual const char *getMD5() = 0;

  static int serializeAvrFloat64(unsigned char *out, float f) {
    uint32_t bits;
    memcpy(&bits, &f, 4);
    uint32_t sign = bits >> 31, exp = (bits >> 23) & 0xFF, mant = bits & 0x7FFFFF;
    uint32_t hi, lo;
    if (exp == 0) {                 /* zero (denormals flushed) */
      hi = 0; lo = 0;
    } else if (exp == 0xFF) {       /* infinity, NaN */
      hi = 0x7FF00000UL | (mant >> 3); lo = mant << 29;
    } else {
      hi = ((exp + 1023 - 127) << 20) | (mant >> 3); lo = mant << 29;
    }
    hi |= sign << 31;
    memcpy(out, &lo, 4);
    memcpy(out + 4, &hi, 4);
    return 8;
  }

  static int deserializeAvrFloat64(const unsigned char *in, float *f) {
    uint32_t lo, hi;
    memcpy(&lo, in, 4);
    memcpy(&hi, in + 4, 4);
    uint32_t sign = hi >> 31, exp = (hi >> 20) & 0x7FF;
    uint32_t mant = ((hi & 0xFFFFF) << 3) | (lo >> 29);   /* top 23 bits, truncated */
    uint32_t bits;
    if (exp == 0x7FF) {
      bits = 0x7F800000UL | (mant ? 0x400000UL : 0);
    } else {
      int32_t e = (int32_t)exp - 1023 + 127;
      if (exp == 0 || e <= 0) bits = 0;
      else if (e >= 0xFF) bits = 0x7F800000UL;
      else bits = ((uint32_t)e << 23) | mant;
    }
    bits |= sign << 31;
    memcpy(f, &bits, 4);
    return 8;
  }

  static int serializeString(unsigned char *out, const char *s) {
    uint32_t n = strlen(s);
    memcpy(out, &n, 4);
    memcpy(out + 4, s, n);
    return 4 + n;
  }

  static uint32_t readUint32(const unsigned char *in) {
    uint32_t v;
    memcpy(&v, in, 4);
    return v;
  }

  static int writeUint32(unsigned char *out, uint32_t v) {
    memcpy(out, &v, 4);
    return 4;
  }
};

}  // namespace ros

#endif
