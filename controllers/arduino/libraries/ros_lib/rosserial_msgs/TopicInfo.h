/* rosserial_msgs/TopicInfo (amr-twin's own code): what a topic request is answered with.
 * uint16 topic_id, string topic_name, string message_type, string md5sum, int32 buffer_size. */
#ifndef AMR_TWIN_ROSSERIAL_MSGS_TOPICINFO_H
#define AMR_TWIN_ROSSERIAL_MSGS_TOPICINFO_H

#include "ros/msg.h"

namespace rosserial_msgs {

class TopicInfo : public ros::Msg {
public:
  enum { ID_PUBLISHER = 0, ID_SUBSCRIBER = 1, ID_TIME = 10, ID_TX_STOP = 11 };
  uint16_t topic_id;
  const char *topic_name;
  const char *message_type;
  const char *md5sum;
  int32_t buffer_size;

  TopicInfo() : topic_id(0), topic_name(""), message_type(""), md5sum(""), buffer_size(0) {}

  virtual int serializedLength() const {
    return 2 + 4 + strlen(topic_name) + 4 + strlen(message_type) + 4 + strlen(md5sum) + 4;
  }
  virtual int serialize(unsigned char *out) const {
    int o = 0;
    out[o++] = topic_id & 0xFF;
    out[o++] = (topic_id >> 8) & 0xFF;
    o += serializeString(out + o, topic_name);
    o += serializeString(out + o, message_type);
    o += serializeString(out + o, md5sum);
    o += writeUint32(out + o, (uint32_t)buffer_size);
    return o;
  }

  virtual int deserialize(unsigned char *) { return 0; }  /* the board only sends these */
  virtual const char *getType() { return "rosserial_msgs/TopicInfo"; }
  virtual const char *getMD5() { return "0ad51f88fc44892f8c10684077646005"; }
};

}  // namespace rosserial_msgs

#endif
