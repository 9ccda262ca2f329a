#include "core/net/curve_keys.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <functional>

#include "core/base/atomic_file.h"
#include "core/base/error.h"

namespace lumistage {
namespace {

namespace fs = std::filesystem;

class CurveKeysTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("lumistage_keys_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string errorOf(const std::function<void()>& f) {
    try {
      f();
    } catch (const Error& e) {
      return e.what();
    }
    return "(no error)";
  }

  fs::path dir_;
};

TEST_F(CurveKeysTest, KeyPairsAreZ85AndDistinct) {
  const CurveKeyPair a = generateCurveKeyPair(), b = generateCurveKeyPair();
  EXPECT_TRUE(isZ85Key(a.public_key));
  EXPECT_TRUE(isZ85Key(a.secret_key));
  EXPECT_NE(a.public_key, b.public_key);
  EXPECT_FALSE(isZ85Key(a.public_key.substr(1)));
  EXPECT_FALSE(isZ85Key(std::string(40, '~')));
  EXPECT_FALSE(isZ85Key(std::string(40, '#')));  // past 2^32 a word: not Z85
}

TEST_F(CurveKeysTest, InitWritesStudioAndNodeKeysWithSecretsPrivate) {
  KeyStore store(dir_);
  store.init({"node1", "node2"});
  const CurveKeyPair studio = store.studioKey();
  const CurveKeyPair node1 = store.nodeKey("node1");
  const std::vector<AuthorizedNode> authorized = store.authorizedNodes();
  ASSERT_EQ(authorized.size(), 2u);
  EXPECT_EQ(authorized[0].name, "node1");
  EXPECT_EQ(authorized[0].public_key, node1.public_key);
  EXPECT_EQ(authorized[1].public_key, store.nodeKey("node2").public_key);
  EXPECT_NE(studio.public_key, node1.public_key);

  for (const fs::path& secret : {store.studioKeyPath(), store.nodeKeyPath("node1")}) {
    struct stat st {};
    ASSERT_EQ(::stat(secret.c_str(), &st), 0);
    EXPECT_EQ(st.st_mode & 0777, 0600u) << secret;
  }

  // Never a new studio key by accident; add-node is the way to grow.
  EXPECT_NE(errorOf([&] { store.init({"node3"}); }).find("a studio key exists already"),
            std::string::npos);
  EXPECT_EQ(store.studioKey().public_key, studio.public_key);
  const CurveKeyPair node3 = store.addNode("node3");
  EXPECT_EQ(store.authorizedNodes().size(), 3u);
  EXPECT_EQ(store.nodeKey("node3").secret_key, node3.secret_key);
  EXPECT_NE(errorOf([&] { store.addNode("node3"); }).find("has a key already"), std::string::npos);
  EXPECT_NE(errorOf([&] { store.addNode("../evil"); }).find("expected 1 to 64 letters"),
            std::string::npos);
  // A node's key where there is no studio key (a mistyped --dir): refused, nothing written. The
  // store made then held node keys that no studio admits.
  KeyStore elsewhere(dir_ / "elsewhere");
  EXPECT_NE(errorOf([&] { elsewhere.addNode("node4"); }).find("no studio key here"),
            std::string::npos);
  EXPECT_FALSE(fs::exists(dir_ / "elsewhere"));
  EXPECT_NE(errorOf([&] {
              elsewhere.init({"n1", "n1"});
            }).find("node 'n1' is named twice"),
            std::string::npos);
}

TEST_F(CurveKeysTest, BadKeyFilesNameFileLineAndKey) {
  fs::create_directories(dir_);
  const CurveKeyPair keys = generateCurveKeyPair();
  const fs::path file = dir_ / "bad.key";

  writeFileAtomically(file, "# comment\npublic = " + keys.public_key + "\nsecret = short\n");
  EXPECT_EQ(errorOf([&] { loadKeyPair(file); }),
            file.string() + ":3: secret: expected a 40-character Z85 CURVE key, got 5 characters");

  writeFileAtomically(file, "public = " + keys.public_key + "\n");
  EXPECT_EQ(errorOf([&] { loadKeyPair(file); }),
            file.string() + ": secret: missing, expected 'secret = KEY'");

  writeFileAtomically(file, "public: none\n");
  EXPECT_EQ(errorOf([&] { loadKeyPair(file); }),
            file.string() + ":1: expected 'public = KEY' or 'secret = KEY'");

  const CurveKeyPair other = generateCurveKeyPair();
  writeFileAtomically(file,
                      "public = " + other.public_key + "\nsecret = " + keys.secret_key + "\n");
  EXPECT_EQ(errorOf([&] { loadKeyPair(file); }),
            file.string() + ": public: does not belong to the secret key");

  writeFileAtomically(file, "public = " + keys.public_key + "\ncolour = blue\n");
  EXPECT_EQ(errorOf([&] { loadPublicKey(file); }), file.string() + ":2: colour: unknown key");

  EXPECT_NE(errorOf([&] { loadPublicKey(dir_ / "missing.pub"); }).find("cannot open"),
            std::string::npos);
  EXPECT_NE(errorOf([&] { KeyStore(dir_ / "none").authorizedNodes(); }).find("no such folder"),
            std::string::npos);
}

}  // namespace
}  // namespace lumistage

namespace lumistage {
namespace {

// Under umask 000 the key folders came out writable by anyone; a secret key made readable by
// others was used without a word.
TEST(CurveKeyPermissions, FoldersArePrivateWhateverTheUmaskAndLooseSecretsAreSaid) {
  const fs::path dir =
      fs::temp_directory_path() / ("lumistage_key_permissions_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const mode_t old_umask = ::umask(0);
  KeyStore store(dir);
  store.init({"node1"});
  store.addNode("node2");
  ::umask(old_umask);
  for (const fs::path& folder : {dir, dir / "nodes", dir / "authorized"}) {
    struct stat st {};
    ASSERT_EQ(::stat(folder.c_str(), &st), 0);
    EXPECT_EQ(st.st_mode & 0777, 0700u) << folder;
    EXPECT_EQ(keyPermissionProblem(folder), "");
  }
  for (const fs::path& secret :
       {store.studioKeyPath(), store.nodeKeyPath("node1"), store.nodeKeyPath("node2")}) {
    struct stat st {};
    ASSERT_EQ(::stat(secret.c_str(), &st), 0);
    EXPECT_EQ(st.st_mode & 0777, 0600u) << secret;
    EXPECT_EQ(keyPermissionProblem(secret), "");
  }
  // chmod 644 on a secret, 777 on the folder the studio admits keys from: said.
  fs::permissions(store.studioKeyPath(), fs::perms(0644));
  EXPECT_NE(keyPermissionProblem(store.studioKeyPath())
                .find("studio.key: the secret key is "
                      "readable or writable by others "
                      "(mode 0644)"),
            std::string::npos)
      << keyPermissionProblem(store.studioKeyPath());
  EXPECT_NO_THROW(store.studioKey());  // used still, with the warning
  fs::permissions(dir / "authorized", fs::perms(0777));
  EXPECT_NE(keyPermissionProblem(dir / "authorized").find("writable by others (mode 0777)"),
            std::string::npos);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace lumistage
