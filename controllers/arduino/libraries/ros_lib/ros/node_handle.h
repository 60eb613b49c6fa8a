/* ros/node_handle.h: the rosserial serial protocol, client side (amr-twin's own code, written from
 * the protocol's description, wiki.ros.org/rosserial/Overview/Protocol).
 *
 * Frame: 0xff | 0xfe | len lo | len hi | len checksum | topic lo | topic hi | message | checksum,
 * len checksum = 255 - (len lo + len hi) % 256, checksum = 255 - (topic bytes + message) % 256.
 * Topic ids: 0 = topic negotiation (rosserial_msgs/TopicInfo), 10 = time, 11 = TX_STOP;
 * subscribers 100.., publishers 100 + MAX_SUBSCRIBERS.., as rosserial assigns them.
 *
 * What the host (rosserial_python's serial_node.py, or the twin's own host) relies on:
 * - Negotiation: a frame on id 0 from the host is answered with one TopicInfo per publisher (id 0)
 *   and per subscriber (id 1) and a time request; from then on the client is configured.
 * - No publishing before configured: publish() on an application topic (id >= 100) drops the
 *   message until the host has negotiated (serial_node answers an unknown topic id with a new
 *   topic request, i.e. it renegotiates).
 * - Time sync: a configured client sends a time request (an empty std_msgs/Time on id 10) every
 *   SYNC_PERIOD_MS; the host answers with its time, which now() keeps (offset from millis()).
 *   serial_node drops sync and renegotiates after 15 s without a time request. A client that got
 *   no answer for SYNC_TIMEOUT_MS takes the host for gone and stops publishing until it
 *   negotiates again; TX_STOP from the host (it shuts down) does the same at once.
 * - Interrupts: no frame is written from inside an interrupt (or any section with interrupts
 *   off). A publish() made there is kept as a finished frame (ISR_OUTPUT_SIZE bytes in all; more
 *   is dropped and counted) and written from main context: at the next spinOnce() or publish(),
 *   or by yield(), which Arduino's delay() calls while it waits (ros.h), so a ramp's delay() does
 *   not hold the frame. spinOnce() inside an interrupt does nothing: reading and the protocol's
 *   replies happen in main context only.
 * spinOnce() reads what Serial holds, frame by frame; a complete frame with a good checksum calls
 * its subscriber; a frame with a bad length or checksum is dropped; a frame left unfinished for
 * SERIAL_MSG_TIMEOUT_MS is abandoned. A call that finds nothing to read ends with
 * Hardware::idle() (ArduinoHardware.h).
 *
 * AMR_TWIN_ROS_CONFIGURED_AT_START (a define of the twin's own runs, where the twin is the host
 * and knows the topic table): start configured, as if the host had negotiated before t = 0. */
#ifndef AMR_TWIN_ROS_NODE_HANDLE_H
#define AMR_TWIN_ROS_NODE_HANDLE_H

#include <avr/interrupt.h>
#include <avr/io.h>

#include "ros/msg.h"
#include "ros/publisher.h"
#include "ros/subscriber.h"
#include "ros/time.h"
#include "rosserial_msgs/TopicInfo.h"

namespace ros {

const uint8_t PROTOCOL_VER = 0xfe;
const unsigned long SERIAL_MSG_TIMEOUT_MS = 20;
const unsigned long SYNC_PERIOD_MS = 5000;
const unsigned long SYNC_TIMEOUT_MS = 15000;
const int ISR_OUTPUT_SIZE = 64;

inline bool interruptsOn() { return SREG & _BV(SREG_I); }

template <class Hardware, int MAX_SUBSCRIBERS = 25, int MAX_PUBLISHERS = 25,
          int INPUT_SIZE = 512, int OUTPUT_SIZE = 512>
class NodeHandle_ : public NodeHandleBase_ {
public:
  NodeHandle_() : configured_(false), mode_(MODE_FIRST_FF), bytes_(0), index_(0), topic_(0),
                  checksum_(0), last_msg_timeout_time_(0), last_sync_time_(0), last_sync_receive_time_(0),
                  rt_time_(0), sec_offset_(0), nsec_offset_(0), isr_len_(0), isr_dropped_(0) {
    for (int i = 0; i < MAX_PUBLISHERS; i++) publishers_[i] = 0;
    for (int i = 0; i < MAX_SUBSCRIBERS; i++) subscribers_[i] = 0;
  }

  Hardware *getHardware() { return &hardware_; }

  void initNode() {
    hardware_.init();
    mode_ = MODE_FIRST_FF;
    activeNodeHandle() = this;
#ifdef AMR_TWIN_ROS_CONFIGURED_AT_START
    configured_ = true;
    last_sync_time_ = last_sync_receive_time_ = hardware_.time();
#endif
  }

  bool connected() { return configured_; }
  /* Frames published inside interrupts that did not fit ISR_OUTPUT_SIZE (lost). */
  unsigned int isrDropped() { return isr_dropped_; }

  /* The host's time: the last answer to a time request plus the millis() since it was asked. */
  Time now() {
    unsigned long ms = hardware_.time();
    Time t;
    t.sec = ms / 1000 + sec_offset_;
    t.nsec = (ms % 1000) * 1000000UL + nsec_offset_;
    t.normalize();
    return t;
  }

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
    if (!interruptsOn()) return;  /* inside an interrupt: reading and replies wait for main context */
    flushDeferred();
    unsigned long now = hardware_.time();
    if (mode_ != MODE_FIRST_FF && (long)(now - last_msg_timeout_time_) > 0) mode_ = MODE_FIRST_FF;
    if (configured_ && now - last_sync_receive_time_ > SYNC_TIMEOUT_MS) configured_ = false;
    if (configured_ && now - last_sync_time_ > SYNC_PERIOD_MS) {
      requestSyncTime();
      last_sync_time_ = now;
    }
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
    if (id >= 100 && !configured_) return 0;  /* the host does not know the topic yet */
    if (!interruptsOn()) return deferFrame(id, msg);
    flushDeferred();
    int n = frameInto(message_out_, OUTPUT_SIZE, id, msg);
    if (n) hardware_.write(message_out_, n);
    return n;
  }

  /* Write the frames published inside interrupts (main context only; ros.h's yield() calls it). */
  virtual void flushDeferred() {
    if (!isr_len_ || !interruptsOn()) return;
    unsigned char frames[ISR_OUTPUT_SIZE];
    uint8_t sreg = SREG;
    cli();
    int n = isr_len_;
    memcpy(frames, isr_out_, n);
    isr_len_ = 0;
    SREG = sreg;
    hardware_.write(frames, n);
  }

private:
  enum { MODE_FIRST_FF, MODE_PROTOCOL_VER, MODE_SIZE_L, MODE_SIZE_H, MODE_SIZE_CHECKSUM,
         MODE_TOPIC_L, MODE_TOPIC_H, MODE_MESSAGE, MODE_MSG_CHECKSUM };

  /* The frame carrying `msg` on topic `id` into `out` (at most `size` bytes): its length, 0 if too long. */
  static int frameInto(unsigned char *out, int size, int id, const Msg *msg) {
    if (size < 8 || msg->serializedLength() + 8 > size) return 0;
    int l = msg->serialize(out + 7);
    out[0] = 0xff;
    out[1] = PROTOCOL_VER;
    out[2] = l & 0xFF;
    out[3] = (l >> 8) & 0xFF;
    out[4] = 255 - ((out[2] + out[3]) % 256);
    out[5] = id & 0xFF;
    out[6] = (id >> 8) & 0xFF;
    int chk = 0;
    for (int i = 5; i < l + 7; i++) chk += out[i];
    out[l + 7] = 255 - (chk % 256);
    return l + 8;
  }

  int deferFrame(int id, const Msg *msg) {
    int n = frameInto(isr_out_ + isr_len_, ISR_OUTPUT_SIZE - isr_len_, id, msg);
    if (n == 0) {
      isr_dropped_++;
      return 0;
    }
    isr_len_ += n;
    return n;
  }

  void requestSyncTime() {
    Time empty;
    publish(rosserial_msgs::TopicInfo::ID_TIME, &empty);
    rt_time_ = hardware_.time();
  }

  void syncTime(const unsigned char *data) {
    /* the host's time when it answered, taken as the time it was asked plus half the round trip */
    Time t;
    t.deserialize((unsigned char *)data);
    unsigned long now = hardware_.time();
    unsigned long half = (now - rt_time_) / 2;
    unsigned long at = rt_time_ + half;
    long sec = (long)t.sec - (long)(at / 1000);
    long nsec = (long)t.nsec - (long)((at % 1000) * 1000000UL);
    while (nsec < 0) { nsec += 1000000000L; sec--; }
    sec_offset_ = sec;
    nsec_offset_ = nsec;
    last_sync_receive_time_ = now;
  }

  void dispatch() {
    if (topic_ == rosserial_msgs::TopicInfo::ID_PUBLISHER) {
      unsigned long now = hardware_.time();
      last_sync_time_ = last_sync_receive_time_ = now;
      configured_ = true;
      negotiateTopics();
      requestSyncTime();
    } else if (topic_ == rosserial_msgs::TopicInfo::ID_TIME) {
      syncTime(message_in_);
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
  unsigned long last_sync_time_;
  unsigned long last_sync_receive_time_;
  unsigned long rt_time_;
  long sec_offset_;
  long nsec_offset_;
  volatile int isr_len_;
  unsigned int isr_dropped_;
  unsigned char message_in_[INPUT_SIZE];
  unsigned char message_out_[OUTPUT_SIZE];
  unsigned char isr_out_[ISR_OUTPUT_SIZE];
};

}  // namespace ros

#endif
