/* ros/node_handle.h: the rosserial serial protocol, client side (amr-twin's own code).
 *
 * Frame: 0xff | 0xfe | len lo | len hi | len checksum | topic lo | topic hi | message | checksum,
 * len checksum = 255 - (len lo + len hi) % 256, checksum = 255 - (topic bytes + message) % 256.
 * Topic ids: 0 = topic negotiation (rosserial_msgs/TopicInfo), subscribers 100.., publishers
 * 100 + MAX_SUBSCRIBERS.., as rosserial assigns them. spinOnce() reads what Serial holds,
 * frame by frame; a complete frame with a good checksum calls its subscriber; a frame with a
 * bad length or checksum is dropped; a frame left unfinished for SERIAL_MSG_TIMEOUT_MS is
 * abandoned. A request for topics (topic 0) is answered with one TopicInfo per publisher and
 * subscriber. A call that finds nothing to read ends with Hardware::idle() (ArduinoHardware.h). */
#ifndef AMR_TWIN_ROS_NODE_HANDLE_H
#define AMR_TWIN_ROS_NODE_HANDLE_H

#include "ros/msg.h"
#include "ros/publisher.h"
#include "ros/subscriber.h"
#include "rosserial_msgs/TopicInfo.h"

namespace ros {

const uint8_t PROTOCOL_VER = 0xfe;
const unsigned long SERIAL_MSG_TIMEOUT_MS = 20;

template <class Hardware, int MAX_SUBSCRIBERS = 25, int MAX_PUBLISHERS = 25,
          int INPUT_SIZE = 512, int OUTPUT_SIZE = 512>
class NodeHandle_ : public NodeHandleBase_ {
public:
  NodeHandle_() : configured_(false), mode_(MODE_FIRST_FF), bytes_(0), index_(0), topic_(0),
                  checksum_(0), last_msg_timeout_time_(0) {
    for (int i = 0; i < MAX_PUBLISHERS; i++) publishers_[i] = 0;
    for (int i = 0; i < MAX_SUBSCRIBERS; i++) subscribers_[i] = 0;
  }

  Hardware *getHardware() { return &hardware_; }
  void initNode() { hardware_.init(); mode_ = MODE_FIRST_FF; }
  bool connected() { return configured_; }

  bool advertise(Publisher &p) {
    for (int i = 0; i < MAX_PUBLISHERS; i++) {
      if (publishers_[i] == 0) {
        publishers_[i] = &p;
        p.id_ = i + 100 + MAX_SUBSCRIBERS;
        p.nh_ = this;
        return true;
      }
    }
    return false;
  }

  template <typename SubscriberT>
  bool subscribe(SubscriberT &s) {
    for (int i = 0; i < MAX_SUBSCRIBERS; i++) {
      if (subscribers_[i] == 0) {
        subscribers_[i] = &s;
        s.id_ = i + 100;
        return true;
      }
    }
    return false;
  }

  void spinOnce() {
    unsigned long now = hardware_.time();
    if (mode_ != MODE_FIRST_FF && (long)(now - last_msg_timeout_time_) > 0) mode_ = MODE_FIRST_FF;
    bool got = false;
    while (true) {
      int data = hardware_.read();
      if (data < 0) break;
      got = true;
      checksum_ += data;
      switch (mode_) {
        case MODE_MESSAGE:
          message_in_[index_++] = data;
          if (--bytes_ == 0) mode_ = MODE_MSG_CHECKSUM;
          break;
        case MODE_FIRST_FF:
          if (data == 0xff) {
            mode_ = MODE_PROTOCOL_VER;
            last_msg_timeout_time_ = now + SERIAL_MSG_TIMEOUT_MS;
          }
          break;
        case MODE_PROTOCOL_VER:
          mode_ = data == PROTOCOL_VER ? MODE_SIZE_L : MODE_FIRST_FF;
          break;
        case MODE_SIZE_L:
          bytes_ = data;
          index_ = 0;
          checksum_ = data;
          mode_ = MODE_SIZE_H;
          break;
        case MODE_SIZE_H:
          bytes_ += data << 8;
          mode_ = MODE_SIZE_CHECKSUM;
          break;
        case MODE_SIZE_CHECKSUM:
          mode_ = (checksum_ % 256 == 255) ? MODE_TOPIC_L : MODE_FIRST_FF;
          break;
        case MODE_TOPIC_L:
          topic_ = data;
          checksum_ = data;
          mode_ = MODE_TOPIC_H;
          break;
        case MODE_TOPIC_H:
          topic_ += data << 8;
          mode_ = bytes_ == 0 ? MODE_MSG_CHECKSUM : MODE_MESSAGE;
          if (bytes_ > INPUT_SIZE) mode_ = MODE_FIRST_FF;
          break;
        case MODE_MSG_CHECKSUM:
          mode_ = MODE_FIRST_FF;
          if (checksum_ % 256 == 255) dispatch();
          break;
      }
    }
    if (!got) hardware_.idle();
  }

  virtual int publish(int id, const Msg *msg) {
    int l = msg->serialize(message_out_ + 7);
    if (l + 8 > OUTPUT_SIZE) return 0;
    message_out_[0] = 0xff;
    message_out_[1] = PROTOCOL_VER;
    message_out_[2] = l & 0xFF;
    message_out_[3] = (l >> 8) & 0xFF;
    message_out_[4] = 255 - ((message_out_[2] + message_out_[3]) % 256);
    message_out_[5] = id & 0xFF;
    message_out_[6] = (id >> 8) & 0xFF;
    int chk = 0;
    for (int i = 5; i < l + 7; i++) chk += message_out_[i];
    message_out_[l + 7] = 255 - (chk % 256);
    hardware_.write(message_out_, l + 8);
    return l + 8;
  }

private:
  enum { MODE_FIRST_FF, MODE_PROTOCOL_VER, MODE_SIZE_L, MODE_SIZE_H, MODE_SIZE_CHECKSUM,
         MODE_TOPIC_L, MODE_TOPIC_H, MODE_MESSAGE, MODE_MSG_CHECKSUM };

  void dispatch() {
    if (topic_ == rosserial_msgs::TopicInfo::ID_PUBLISHER) {
      negotiateTopics();
    } else if (topic_ == rosserial_msgs::TopicInfo::ID_TX_STOP) {
      configured_ = false;
    } else if (topic_ >= 100 && topic_ < 100 + MAX_SUBSCRIBERS && subscribers_[topic_ - 100]) {
      subscribers_[topic_ - 100]->callback(message_in_);
    }
  }

  void negotiateTopics() {
    rosserial_msgs::TopicInfo ti;
    for (int i = 0; i < MAX_PUBLISHERS; i++) {
      if (publishers_[i] == 0) continue;
      ti.topic_id = publishers_[i]->id_;
      ti.topic_name = publishers_[i]->topic_;
      ti.message_type = publishers_[i]->msg_->getType();
      ti.md5sum = publishers_[i]->msg_->getMD5();
      ti.buffer_size = OUTPUT_SIZE;
      publish(rosserial_msgs::TopicInfo::ID_PUBLISHER, &ti);
    }
    for (int i = 0; i < MAX_SUBSCRIBERS; i++) {
      if (subscribers_[i] == 0) continue;
      ti.topic_id = subscribers_[i]->id_;
      ti.topic_name = subscribers_[i]->topic_;
      ti.message_type = subscribers_[i]->getMsgType();
      ti.md5sum = subscribers_[i]->getMsgMD5();
      ti.buffer_size = INPUT_SIZE;
      publish(rosserial_msgs::TopicInfo::ID_SUBSCRIBER, &ti);
    }
    configured_ = true;
  }

  Hardware hardware_;
  Publisher *publishers_[MAX_PUBLISHERS];
  Subscriber_ *subscribers_[MAX_SUBSCRIBERS];
  bool configured_;
  int mode_;
  int bytes_;
  int index_;
  int topic_;
  int checksum_;
  unsigned long last_msg_timeout_time_;
  unsigned char message_in_[INPUT_SIZE];
  unsigned char message_out_[OUTPUT_SIZE];
};

}  // namespace ros

#endif
