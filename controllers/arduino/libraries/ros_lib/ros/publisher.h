/* ros/publisher.h (amr-twin's own code). */
#ifndef AMR_TWIN_ROS_PUBLISHER_H
#define AMR_TWIN_ROS_PUBLISHER_H

#include "ros/msg.h"

namespace ros {

class NodeHandleBase_ {
public:
  virtual int publish(int id, const Msg *msg) = 0;
  virtual void flushDeferred() = 0;
};

/* The NodeHandle that initNode() made active: ros.h's yield() writes its deferred frames. */
inline NodeHandleBase_ *&activeNodeHandle() {
  static NodeHandleBase_ *active = 0;
  return active;
}

class Publisher {
public:
  Publisher(const char *topic_name, Msg *msg) : topic_(topic_name), msg_(msg), id_(0), nh_(0) {}
  int publish(const Msg *msg) { return nh_ ? nh_->publish(id_, msg) : 0; }

  const char *topic_;
  Msg *msg_;
  int id_;
  NodeHandleBase_ *nh_;
};

}  // namespace ros

#endif
