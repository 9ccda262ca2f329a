#include "core/net/transport.h"

#include <gtest/gtest.h>

#include <thread>

#include "core/base/error.h"

namespace lumistage {
namespace {

using std::chrono::milliseconds;

// Long enough for a handshake on a loaded machine; only the refused cases wait it out.
constexpr milliseconds kPatience{3000};
constexpr milliseconds kRefusedWait{500};

Message hello(const std::string& node) {
  Message m;
  m.sender = node;
  m.body = HelloData{node, {"cam01", "cam02", "cam03"}, kProtocolVersion, {}};
  return m;
}

struct Keys {
  CurveKeyPair studio = generateCurveKeyPair();
  CurveKeyPair node1 = generateCurveKeyPair();
};

StudioEndpointConfig curveStudio(const Keys& keys) {
  StudioEndpointConfig config;
  config.bind = "tcp://127.0.0.1:*";
  config.studio_key = keys.studio;
  config.authorized = {{"node1", keys.node1.public_key}};
  return config;
}

NodeEndpointConfig curveNode(const StudioEndpoint& studio, const std::string& name,
                             const CurveKeyPair& key, const std::string& studio_public_key) {
  NodeEndpointConfig config;
  config.connect = studio.endpoint();
  config.name = name;
  config.node_key = key;
  config.studio_public_key = studio_public_key;
  return config;
}

TEST(Transport, AuthorizedNodeExchangesMessagesBothWaysUnderCurve) {
  const Keys keys;
  StudioEndpoint studio(curveStudio(keys));
  NodeEndpoint node(curveNode(studio, "node1", keys.node1, keys.studio.public_key));

  ASSERT_TRUE(node.send(hello("node1"), kPatience));
  const std::optional<ReceivedMessage> in = studio.receive(kPatience);
  ASSERT_TRUE(in.has_value());
  ASSERT_TRUE(in->result.ok()) << in->result.error;
  EXPECT_EQ(in->node, "node1");  // from the key the handshake proved
  EXPECT_EQ(in->peer, "node1");
  EXPECT_EQ(*in->result.message, hello("node1"));

  Message pose;
  pose.sender = "studio";
  pose.frame_id = 7;
  pose.body = PoseData{{0, 0, 1}, std::vector<float>(66, 0.5f)};
  ASSERT_TRUE(studio.send(in->peer, pose, kPatience));
  const std::optional<DecodeResult> back = node.receive(kPatience);
  ASSERT_TRUE(back.has_value());
  ASSERT_TRUE(back->ok()) << back->error;
  EXPECT_EQ(*back->message, pose);

  EXPECT_FALSE(studio.send("nobody", pose, milliseconds(100)));
  EXPECT_EQ(studio.refusalCount(), 0);
}

TEST(Transport, NodeWithAnUnknownKeyIsRefusedAndReported) {
  const Keys keys;
  StudioEndpoint studio(curveStudio(keys));
  const CurveKeyPair stranger = generateCurveKeyPair();
  NodeEndpoint node(curveNode(studio, "node1", stranger, keys.studio.public_key));

  EXPECT_FALSE(node.send(hello("node1"), kRefusedWait));
  EXPECT_FALSE(studio.receive(milliseconds(100)).has_value());
  for (int i = 0; i < 100 && studio.refusalCount() == 0; ++i) {
    std::this_thread::sleep_for(milliseconds(20));
  }
  const std::vector<Refusal> refusals = studio.refusals();
  ASSERT_FALSE(refusals.empty());
  EXPECT_EQ(refusals[0].address, "127.0.0.1");
  EXPECT_EQ(refusals[0].key_prefix, stranger.public_key.substr(0, 8));
  EXPECT_EQ(refusals[0].reason,
            "node key " + stranger.public_key.substr(0, 8) + " is not authorized");
}

TEST(Transport, NodeThatTrustsTheWrongStudioKeyGetsNothingThrough) {
  const Keys keys;
  StudioEndpoint studio(curveStudio(keys));
  NodeEndpoint node(curveNode(studio, "node1", keys.node1, generateCurveKeyPair().public_key));
  EXPECT_FALSE(node.send(hello("node1"), kRefusedWait));
  EXPECT_FALSE(studio.receive(milliseconds(100)).has_value());
}

TEST(Transport, MalformedMessageIsDroppedAndCountedAgainstItsSender) {
  const Keys keys;
  StudioEndpoint studio(curveStudio(keys));
  // It calls itself something else: the studio names it by its key.
  NodeEndpoint node(curveNode(studio, "impostor", keys.node1, keys.studio.public_key));

  const std::vector<uint8_t> garbage = {1, 2, 3, 4, 'L', 'U', 'M', 'I', 9, 9, 9, 9};
  ASSERT_TRUE(node.send(garbage, kPatience));
  std::optional<ReceivedMessage> in = studio.receive(kPatience);
  ASSERT_TRUE(in.has_value());
  EXPECT_FALSE(in->result.ok());
  EXPECT_EQ(in->node, "node1");
  EXPECT_NE(in->result.error.find("malformed"), std::string::npos) << in->result.error;
  EXPECT_EQ(studio.badMessages(), (std::map<std::string, int64_t>{{"node1", 1}}));

  // The connection survives: the next good message arrives.
  ASSERT_TRUE(node.send(hello("node1"), kPatience));
  in = studio.receive(kPatience);
  ASSERT_TRUE(in.has_value());
  EXPECT_TRUE(in->result.ok()) << in->result.error;
}

TEST(Transport, PlainModeWorksOnlyWhenBothSidesAskForIt) {
  StudioEndpointConfig plain_studio;
  plain_studio.bind = "tcp://127.0.0.1:*";
  plain_studio.security = TransportSecurity::kPlain;
  {
    StudioEndpoint studio(plain_studio);
    NodeEndpointConfig config;
    config.connect = studio.endpoint();
    config.name = "node1";
    config.security = TransportSecurity::kPlain;
    NodeEndpoint node(config);
    ASSERT_TRUE(node.send(hello("node1"), kPatience));
    const std::optional<ReceivedMessage> in = studio.receive(kPatience);
    ASSERT_TRUE(in.has_value());
    EXPECT_TRUE(in->result.ok());
    EXPECT_EQ(in->node, "node1");
  }
  const Keys keys;
  {
    // A CURVE studio does not talk to a plain node...
    StudioEndpoint studio(curveStudio(keys));
    NodeEndpointConfig config;
    config.connect = studio.endpoint();
    config.name = "node1";
    config.security = TransportSecurity::kPlain;
    NodeEndpoint node(config);
    EXPECT_FALSE(node.send(hello("node1"), kRefusedWait));
    EXPECT_FALSE(studio.receive(milliseconds(100)).has_value());
  }
  {
    // ...and a CURVE node does not talk to a plain studio.
    StudioEndpoint studio(plain_studio);
    NodeEndpoint node(curveNode(studio, "node1", keys.node1, keys.studio.public_key));
    EXPECT_FALSE(node.send(hello("node1"), kRefusedWait));
    EXPECT_FALSE(studio.receive(milliseconds(100)).has_value());
  }
}

TEST(Transport, InvalidKeysAreRefusedUpFront) {
  StudioEndpointConfig config;
  config.bind = "tcp://127.0.0.1:*";
  config.studio_key = {"short", "short"};
  EXPECT_THROW(StudioEndpoint{config}, Error);
}

}  // namespace
}  // namespace lumistage
