/* ros/subscriber.h (amr-twin's own code): a subscriber deserialises into its message and calls back. */
#ifndef AMR_TWIN_ROS_SUBSCRIBER_H
#define AMR_TWIN_ROS_SUBSCRIBER_H

#include "ros/msg.h"

namespace ros {

class Subscriber_ {
public:
  virtual void callback(unsigned char *data) = 0;
  virtual const char *getMsgType() = 0;
  virtual const char *getMsgMD5() = 0;
  const char *topic_;
  int id_;
};

template <typename MsgT>
class Subscriber : public Subscriber_ {
public:
  typedef void (*CallbackT)(const MsgT &);

  Subscriber(const char *topic_name, CallbackT cb) : cb_(cb) {
    topic_ = topic_name;
    id_ = 0;
  }

  virtual void callback(unsigned char *data) {
    msg.deserialize(data);
    cb_(msg);
  }

  virtual const char *getMsgType() { return msg.getType(); }
  virtual const char *getMsgMD5() { return msg.getMD5(); }

  MsgT msg;

private:
  CallbackT cb_;
};

}  // namespace ros

#endif
