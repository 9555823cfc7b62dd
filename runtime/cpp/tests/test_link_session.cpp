#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>

#include "modd/broker/link_session.hpp"
#include "modd/link/auth.hpp"
#include "modd/link/codec.hpp"

using namespace modd;
using namespace modd::broker;
using namespace modd::link;

namespace {

struct Hooks : LinkHooks {
  int configs = 0, auths = 0;
  std::vector<std::string> rejects;
  ConfigAck on_config(const Config& c) override {
    ++configs;
    return {c.config_id, 0, 77};
  }
  AuthOk current_config() override { return AuthOk{{}, 4, 99}; }
  void on_authenticated() override { ++auths; }
  void on_rejected(const std::string& why) override { rejects.push_back(why); }
};

std::vector<Message> frames_of(const std::vector<uint8_t>& out) {
  std::vector<Message> v;
  size_t at = 0;
  while (auto f = split_frame(std::span(out).subspan(at))) {
    at += f->size;
    v.push_back(decode(*f));
  }
  return v;
}

template <typename T>
std::vector<uint8_t> enc(const T& m) {
  std::vector<uint8_t> b;
  encode(b, Message{m});
  return b;
}

const std::string kKey = "k3y";
std::span<const uint8_t> key_bytes() {
  return {reinterpret_cast<const uint8_t*>(kKey.data()), kKey.size()};
}
const Nonce kServerNonce = {5, 5, 5};

}  // namespace

TEST(LinkSession, HandshakeThenPingAndConfig) {
  Hooks h;
  LinkSession s(kKey, h, [] { return kServerNonce; });
  Nonce cn = {1, 2, 3};
  std::vector<uint8_t> out;
  // Bytes may arrive one at a time.
  auto hello = enc(Hello{kVersion, cn});
  for (uint8_t b : hello) ASSERT_TRUE(s.on_bytes(std::span(&b, 1), out));
  auto got = frames_of(out);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(std::get<Challenge>(got[0]).nonce, kServerNonce);
  out.clear();
  ASSERT_TRUE(s.on_bytes(enc(Auth{client_proof(key_bytes(), cn, kServerNonce)}), out));
  auto ok = std::get<AuthOk>(frames_of(out)[0]);
  EXPECT_TRUE(macs_equal(ok.mac, server_proof(key_bytes(), cn, kServerNonce)));
  EXPECT_EQ(ok.config_id, 4);
  EXPECT_EQ(ok.epoch_ns, 99u);
  EXPECT_TRUE(s.ready());
  out.clear();
  Config c;
  c.config_id = 3;
  auto both = enc(Ping{{9}});
  auto cb = enc(c);
  both.insert(both.end(), cb.begin(), cb.end());
  ASSERT_TRUE(s.on_bytes(both, out));
  got = frames_of(out);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(std::get<Pong>(got[0]).payload, std::vector<uint8_t>{9});
  EXPECT_EQ(std::get<ConfigAck>(got[1]).config_id, 3);
  EXPECT_EQ(h.configs, 1);
}

TEST(LinkSession, WrongKeyIsRejectedAndLogged) {
  Hooks h;
  LinkSession s(kKey, h, [] { return kServerNonce; });
  Nonce cn = {1};
  std::vector<uint8_t> out;
  s.on_bytes(enc(Hello{kVersion, cn}), out);
  out.clear();
  std::string wrong = "nope";
  Mac bad = client_proof({reinterpret_cast<const uint8_t*>(wrong.data()), wrong.size()}, cn,
                         kServerNonce);
  EXPECT_FALSE(s.on_bytes(enc(Auth{bad}), out));
  auto e = std::get<ErrorMsg>(frames_of(out)[0]);
  EXPECT_EQ(e.code, static_cast<uint8_t>(ErrorCode::AuthFailed));
  EXPECT_EQ(h.rejects.size(), 1u);
  EXPECT_EQ(h.auths, 0);
}

TEST(LinkSession, NothingBeforeTheHandshake) {
  Hooks h;
  LinkSession s(kKey, h, [] { return kServerNonce; });
  std::vector<uint8_t> out;
  Config c;
  EXPECT_FALSE(s.on_bytes(enc(c), out));
  EXPECT_EQ(std::get<ErrorMsg>(frames_of(out)[0]).code,
            static_cast<uint8_t>(ErrorCode::NotAuthenticated));
  EXPECT_EQ(h.configs, 0);
  Hooks h2;
  LinkSession s2(kKey, h2, [] { return kServerNonce; });
  out.clear();
  EXPECT_FALSE(s2.on_bytes(enc(Hello{2, {}}), out));
  EXPECT_EQ(std::get<ErrorMsg>(frames_of(out)[0]).code, static_cast<uint8_t>(ErrorCode::Version));
  Hooks h3;
  LinkSession s3(kKey, h3, [] { return kServerNonce; });
  out.clear();
  std::vector<uint8_t> garbage = {0xFF, 0xFF, 0x7F};  // a 2 MiB frame announced before auth
  EXPECT_FALSE(s3.on_bytes(garbage, out));
  EXPECT_EQ(std::get<ErrorMsg>(frames_of(out)[0]).code, static_cast<uint8_t>(ErrorCode::BadFrame));
}

// Key files (docs/security.md, "Local surfaces"): regular files of at most 64 KiB,
// never through a final symlink; file:/dev/zero used to exhaust memory.
TEST(KeyFile, RegularBoundedAndNoSymlink) {
  const std::string dir = ::testing::TempDir();
  const std::string key = dir + "/modd_key_ok", big = dir + "/modd_key_big",
                    lnk = dir + "/modd_key_lnk";
  { std::ofstream(key) << "a-secret-of-16-bytes\n"; }
  { std::ofstream(big) << std::string(100000, 'x'); }
  std::remove(lnk.c_str());
  ASSERT_EQ(::symlink(key.c_str(), lnk.c_str()), 0);
  EXPECT_EQ(modd::link::resolve_key("file:" + key), "a-secret-of-16-bytes");
  for (const std::string& ref : {std::string("file:/dev/zero"), "file:" + big, "file:" + lnk})
    EXPECT_THROW(modd::link::resolve_key(ref), modd::Error) << ref;
}

// A 1-byte key was accepted: keys shorter than 16 bytes are refused, saying why.
TEST(KeyFile, AKeyShorterThan16BytesIsRefused) {
  const std::string key = ::testing::TempDir() + "/modd_key_short";
  { std::ofstream(key) << "0123456789abcde\n"; }  // 15 bytes
  ::setenv("MODD_TEST_SHORT_KEY", "k", 1);
  ::setenv("MODD_TEST_KEY_16", "0123456789abcdef", 1);
  for (const std::string& ref : {"file:" + key, std::string("env:MODD_TEST_SHORT_KEY")}) {
    try {
      modd::link::resolve_key(ref);
      ADD_FAILURE() << ref << " accepted";
    } catch (const modd::Error& e) {
      EXPECT_NE(std::string(e.what()).find("at least 16"), std::string::npos) << e.what();
    }
  }
  EXPECT_EQ(modd::link::resolve_key("env:MODD_TEST_KEY_16").size(), 16u);
}
