// The on-board model file written from an ONBOARD (modd/broker/onboard.hpp): the vector's
// zstd frame (contracts/vectors/link/onboard.json, written by the Python codec) gives the
// file's bytes and the digest modd.onboard computes for them; bad payloads are refused
// with a reason; the answers wait for every process's result of that digest.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "modd/broker/onboard.hpp"
#include "modd/util/bytes.hpp"
#include "modd/util/error.hpp"

namespace fs = std::filesystem;
using modd::broker::onboard_answers;
using modd::broker::write_onboard;

namespace {

std::string slurp(const fs::path& p) {
  std::ifstream f(p);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

std::vector<uint8_t> vector_model() {
  auto doc = nlohmann::json::parse(slurp(fs::path(MODD_VECTORS_DIR) / "onboard.json"));
  return modd::from_hex(doc["message"]["model"].get<std::string>());
}

fs::path fresh_dir(const char* name) {
  fs::path d = fs::temp_directory_path() / (std::string("modd-onboard-") + name);
  fs::remove_all(d);
  return d;
}

}  // namespace

TEST(Onboard, WritesTheVectorsModelWithPythonsDigest) {
  fs::path file = fresh_dir("write") / "onboard" / "model.json";
  std::string digest = write_onboard(file.string(), vector_model());
  EXPECT_EQ(digest, "337b3cc77250da14");  // modd.onboard.digest of the same bytes
  EXPECT_EQ(slurp(file), "{\"drone\": {\"name\": \"usv\", \"sensors\": []}}\n");
  EXPECT_EQ(slurp(file.string() + ".valid"), "337b3cc77250da14\n");
}

TEST(Onboard, RefusesWhatIsNotAJsonObjectInAZstdFrame) {
  fs::path file = fresh_dir("bad") / "model.json";
  std::vector<uint8_t> garbage{1, 2, 3, 4};
  EXPECT_THROW(write_onboard(file.string(), garbage), modd::Error);
  auto model = vector_model();
  model.resize(model.size() - 3);  // truncated frame
  EXPECT_THROW(write_onboard(file.string(), model), modd::Error);
  EXPECT_FALSE(fs::exists(file));
}

TEST(Onboard, AnswersWaitForEveryProcessThenSayWhoDidNotAnswer) {
  fs::path file = fresh_dir("answers") / "model.json";
  std::string digest = write_onboard(file.string(), vector_model());
  fs::create_directories(file.parent_path() / "applied");
  std::ofstream(file.parent_path() / "applied" / "sensors.json")
      << R"({"process": "sensors", "digest": ")" << digest << R"(", "ok": true})";
  std::ofstream(file.parent_path() / "applied" / "mavlink.json")
      << R"({"process": "mavlink", "digest": "older", "ok": true})";
  EXPECT_FALSE(onboard_answers(file.string(), digest, false).has_value());
  auto last = nlohmann::json::parse(*onboard_answers(file.string(), digest, true));
  EXPECT_TRUE(last["sensors"]["ok"].get<bool>());
  EXPECT_FALSE(last["mavlink"]["ok"].get<bool>());
  EXPECT_NE(last["mavlink"]["problem"].get<std::string>().find("no answer"), std::string::npos);
  std::ofstream(file.parent_path() / "applied" / "mavlink.json")
      << R"({"process": "mavlink", "digest": ")" << digest << R"(", "ok": true})";
  EXPECT_TRUE(onboard_answers(file.string(), digest, false).has_value());
}
