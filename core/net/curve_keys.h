#pragma once

// CURVE keys of the studio and its nodes, and the folder that keeps them:
//   keys/studio.key            the studio's key pair (secret: mode 600); stays on the studio PC
//   keys/studio.pub            the studio's public key: what every node needs of the studio
//   keys/nodes/<name>.key      each node's key pair, to copy to that node's PC (mode 600)
//   keys/authorized/<name>.pub the node public keys the studio admits
// A node's PC holds a folder of the same layout with studio.pub and its own nodes/<name>.key.
// Removing a node's .pub file locks that node out without touching the others.

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace lumistage {

// Z85 text, 40 characters each (32 bytes of Curve25519 key).
struct CurveKeyPair {
  std::string public_key;
  std::string secret_key;
};

struct AuthorizedNode {
  std::string name;
  std::string public_key;  // Z85
};

// A fresh key pair. Throws Error if libzmq was built without CURVE (libsodium).
CurveKeyPair generateCurveKeyPair();

// 40 characters of the Z85 alphabet that decode to 32 bytes.
bool isZ85Key(std::string_view text);

// Letters, digits, '-' and '_', 1 to 64 characters: node names become file names.
bool isValidNodeName(std::string_view name);

// Key files are "name = value" lines with '#' comments. Loading throws Error naming file:line,
// the key and what was expected.
void saveKeyPair(const std::filesystem::path& path, const CurveKeyPair& keys,
                 std::string_view comment);
// Warns (the log) when the file's secret is readable by others than its owner.
CurveKeyPair loadKeyPair(const std::filesystem::path& path);
void savePublicKey(const std::filesystem::path& path, std::string_view public_key,
                   std::string_view comment);
std::string loadPublicKey(const std::filesystem::path& path);

// What is wrong with the permissions of a secret key file (others may read it) or of a key folder
// (others may add or swap keys in it), in words; empty when nothing is, or it cannot be told.
std::string keyPermissionProblem(const std::filesystem::path& path);

// A key folder as laid out above.
class KeyStore {
 public:
  explicit KeyStore(std::filesystem::path dir) : dir_(std::move(dir)) {}

  // Creates the studio key and one key pair per node. Throws Error if the studio key already
  // exists and `replace` is false: a new studio key locks out every node until its files are
  // copied again, so it never happens by accident.
  void init(const std::vector<std::string>& nodes, bool replace = false);
  // A new node's key pair and its authorization. Throws Error if the node already has a key.
  CurveKeyPair addNode(const std::string& name);

  CurveKeyPair studioKey() const { return loadKeyPair(studioKeyPath()); }
  // What a node needs of the studio: its public key alone (studio.pub), never its secret.
  std::string studioPublicKey() const { return loadPublicKey(studioPublicKeyPath()); }
  CurveKeyPair nodeKey(const std::string& name) const { return loadKeyPair(nodeKeyPath(name)); }
  // Every keys/authorized/*.pub, sorted by name; the name is the file's stem.
  std::vector<AuthorizedNode> authorizedNodes() const;

  std::filesystem::path studioKeyPath() const { return dir_ / "studio.key"; }
  std::filesystem::path studioPublicKeyPath() const { return dir_ / "studio.pub"; }
  std::filesystem::path nodeKeyPath(const std::string& name) const;
  std::filesystem::path authorizedPath(const std::string& name) const;
  const std::filesystem::path& dir() const { return dir_; }

 private:
  std::filesystem::path dir_;
};

}  // namespace lumistage
