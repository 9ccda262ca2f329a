#include "core/net/curve_keys.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <zmq.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <optional>
#include <sstream>

#include "core/base/atomic_file.h"
#include "core/base/error.h"

namespace lumistage {

namespace fs = std::filesystem;

namespace {

constexpr size_t kZ85KeyLength = 40;
constexpr fs::perms kSecretMode = fs::perms::owner_read | fs::perms::owner_write;

struct KeyFileEntry {
  std::string value;
  int line = 0;
};

// "name = value" lines; anything else but comments and blank lines is an error.
std::vector<std::pair<std::string, KeyFileEntry>> parseKeyFile(const fs::path& path) {
  const std::string text = readFile(path);
  std::vector<std::pair<std::string, KeyFileEntry>> entries;
  std::istringstream in(text);
  std::string line;
  int number = 0;
  auto trim = [](std::string s) {
    const auto first = s.find_first_not_of(" \t\r");
    if (first == std::string::npos) return std::string();
    return s.substr(first, s.find_last_not_of(" \t\r") - first + 1);
  };
  while (std::getline(in, line)) {
    ++number;
    line = trim(line);
    if (line.empty() || line[0] == '#') continue;
    const auto eq = line.find('=');
    if (eq == std::string::npos) {
      throw Error(locate(path.string(), number, "", "expected 'public = KEY' or 'secret = KEY'"));
    }
    entries.push_back({trim(line.substr(0, eq)), {trim(line.substr(eq + 1)), number}});
  }
  return entries;
}

std::string requireKey(const fs::path& path,
                       const std::vector<std::pair<std::string, KeyFileEntry>>& entries,
                       const std::string& name) {
  std::optional<KeyFileEntry> found;
  for (const auto& [key, entry] : entries) {
    if (key == name) {
      if (found) throw Error(locate(path.string(), entry.line, name, "given twice"));
      found = entry;
    }
  }
  if (!found) throw Error(locate(path.string(), 0, name, "missing, expected '" + name + " = KEY'"));
  if (!isZ85Key(found->value)) {
    throw Error(
        locate(path.string(), found->line, name,
               "expected a 40-character Z85 CURVE key, got " + std::to_string(found->value.size()) +
                   " characters" +
                   (found->value.size() == kZ85KeyLength ? " outside the Z85 alphabet" : "")));
  }
  return found->value;
}

void rejectUnknown(const fs::path& path,
                   const std::vector<std::pair<std::string, KeyFileEntry>>& entries,
                   std::initializer_list<std::string_view> known) {
  for (const auto& [key, entry] : entries) {
    if (std::find(known.begin(), known.end(), key) == known.end()) {
      throw Error(locate(path.string(), entry.line, key, "unknown key"));
    }
  }
}

// A key folder: one it creates is its owner's only, whatever the umask (under umask 000,
// authorized/ was writable by anyone: a key of their own put there is a node the studio admits).
// One there already is left as it is, and said when others may write to it.
void createDirectories(const fs::path& dir) {
  std::error_code ec;
  const bool created = fs::create_directories(dir, ec);
  if (ec) throw Error(dir.string() + ": cannot create the folder: " + ec.message());
  if (created) {
    fs::permissions(dir, fs::perms::owner_all, fs::perm_options::replace, ec);
    if (ec) throw Error(dir.string() + ": cannot make the folder private: " + ec.message());
  } else if (const std::string problem = keyPermissionProblem(dir); !problem.empty()) {
    spdlog::warn("{}", problem);
  }
}

void requireNodeName(const std::string& name) {
  if (!isValidNodeName(name)) {
    throw Error("node name '" + name +
                "': expected 1 to 64 letters, digits, '-' or '_' (it names the key files)");
  }
}

}  // namespace

CurveKeyPair generateCurveKeyPair() {
  std::array<char, kZ85KeyLength + 1> public_key{}, secret_key{};
  if (zmq_curve_keypair(public_key.data(), secret_key.data()) != 0) {
    throw Error(std::string("cannot create a CURVE key pair: ") + zmq_strerror(zmq_errno()) +
                " (libzmq needs CURVE support, built with libsodium)");
  }
  return {public_key.data(), secret_key.data()};
}

bool isZ85Key(std::string_view text) {
  if (text.size() != kZ85KeyLength) return false;
  static constexpr std::string_view kAlphabet =
      "0123456789abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ.-:+=^!/*?&<>()[]{}@%$#";
  for (char c : text) {
    if (kAlphabet.find(c) == std::string_view::npos) return false;
  }
  // Every 5 characters decode to a 32-bit word; values past 2^32 are not valid Z85.
  const std::string copy(text);
  std::array<uint8_t, 32> bytes{};
  return zmq_z85_decode(bytes.data(), copy.c_str()) != nullptr;
}

bool isValidNodeName(std::string_view name) {
  if (name.empty() || name.size() > 64) return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' ||
           c == '_';
  });
}

void saveKeyPair(const fs::path& path, const CurveKeyPair& keys, std::string_view comment) {
  if (!isZ85Key(keys.public_key) || !isZ85Key(keys.secret_key)) {
    throw Error(path.string() + ": refusing to write a key pair that is not Z85 CURVE keys");
  }
  std::string text = "# " + std::string(comment) +
                     "\n# Secret: keep it on this machine only, readable by its owner only.\n";
  text += "public = " + keys.public_key + "\nsecret = " + keys.secret_key + "\n";
  writeFileAtomically(path, text, {.mode = kSecretMode});
}

std::string keyPermissionProblem(const fs::path& path) {
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (ec) return {};
  const fs::perms p = status.permissions();
  const auto any = [&](fs::perms bits) { return (p & bits) != fs::perms::none; };
  const auto mode = fmt::format("{:04o}", static_cast<unsigned>(p & fs::perms::mask));
  if (fs::is_directory(status)) {
    if (!any(fs::perms::group_write | fs::perms::others_write)) return {};
    return fmt::format(
        "{}: the key folder is writable by others (mode {}): anyone may add a "
        "key the studio admits; chmod 700 it",
        path.string(), mode);
  }
  if (!any(fs::perms::group_read | fs::perms::others_read | fs::perms::group_write |
           fs::perms::others_write))
    return {};
  return fmt::format(
      "{}: the secret key is readable or writable by others (mode {}): anyone who "
      "could read it may pose as its owner; chmod 600 it (and make a new key if it "
      "may have been read)",
      path.string(), mode);
}

CurveKeyPair loadKeyPair(const fs::path& path) {
  if (const std::string problem = keyPermissionProblem(path); !problem.empty())
    spdlog::warn("{}", problem);
  const auto entries = parseKeyFile(path);
  rejectUnknown(path, entries, {"public", "secret"});
  CurveKeyPair keys{requireKey(path, entries, "public"), requireKey(path, entries, "secret")};
  // A public key that does not belong to the secret one fails only at the handshake, with no
  // reason given; catch it here where the file can be named.
  std::array<char, kZ85KeyLength + 1> derived{};
  if (zmq_curve_public(derived.data(), keys.secret_key.c_str()) == 0 &&
      keys.public_key != derived.data()) {
    throw Error(locate(path.string(), 0, "public", "does not belong to the secret key"));
  }
  return keys;
}

void savePublicKey(const fs::path& path, std::string_view public_key, std::string_view comment) {
  if (!isZ85Key(public_key)) {
    throw Error(path.string() + ": refusing to write a public key that is not a Z85 CURVE key");
  }
  writeFileAtomically(path,
                      "# " + std::string(comment) + "\npublic = " + std::string(public_key) + "\n");
}

std::string loadPublicKey(const fs::path& path) {
  const auto entries = parseKeyFile(path);
  rejectUnknown(path, entries, {"public"});
  return requireKey(path, entries, "public");
}

fs::path KeyStore::nodeKeyPath(const std::string& name) const {
  requireNodeName(name);
  return dir_ / "nodes" / (name + ".key");
}

fs::path KeyStore::authorizedPath(const std::string& name) const {
  requireNodeName(name);
  return dir_ / "authorized" / (name + ".pub");
}

void KeyStore::init(const std::vector<std::string>& nodes, bool replace) {
  for (size_t i = 0; i < nodes.size(); ++i) {
    requireNodeName(nodes[i]);
    if (std::find(nodes.begin(), nodes.begin() + i, nodes[i]) != nodes.begin() + i)
      throw Error("node '" + nodes[i] + "' is named twice");
  }
  std::error_code ec;
  if (!replace && fs::exists(studioKeyPath(), ec)) {
    throw Error(studioKeyPath().string() +
                ": a studio key exists already; a new one would lock out every node (use "
                "'keys add-node' for new nodes, or --replace to start over)");
  }
  createDirectories(dir_);
  createDirectories(dir_ / "nodes");
  createDirectories(dir_ / "authorized");
  const CurveKeyPair studio = generateCurveKeyPair();
  saveKeyPair(studioKeyPath(), studio, "Lumistage studio CURVE key pair");
  savePublicKey(studioPublicKeyPath(), studio.public_key,
                "Lumistage studio: copy this file (not studio.key) to every node's key folder");
  for (const std::string& name : nodes) {
    const CurveKeyPair keys = generateCurveKeyPair();
    saveKeyPair(nodeKeyPath(name), keys, "Lumistage node '" + name + "' CURVE key pair");
    savePublicKey(authorizedPath(name), keys.public_key,
                  "Lumistage node '" + name + "': the studio admits this key");
  }
}

CurveKeyPair KeyStore::addNode(const std::string& name) {
  std::error_code ec;
  // A node's key is only of use to the studio whose key is here: without it, a folder of node keys
  // that no studio admits.
  if (!fs::exists(studioKeyPath(), ec)) {
    throw Error(studioKeyPath().string() +
                ": no studio key here; create the keys with 'lumistage keys init' first (or give "
                "--dir the studio's key folder)");
  }
  if (fs::exists(nodeKeyPath(name), ec) || fs::exists(authorizedPath(name), ec)) {
    throw Error(nodeKeyPath(name).string() + ": node '" + name + "' has a key already");
  }
  createDirectories(dir_ / "nodes");
  createDirectories(dir_ / "authorized");
  const CurveKeyPair keys = generateCurveKeyPair();
  saveKeyPair(nodeKeyPath(name), keys, "Lumistage node '" + name + "' CURVE key pair");
  savePublicKey(authorizedPath(name), keys.public_key,
                "Lumistage node '" + name + "': the studio admits this key");
  return keys;
}

std::vector<AuthorizedNode> KeyStore::authorizedNodes() const {
  std::vector<AuthorizedNode> nodes;
  const fs::path dir = dir_ / "authorized";
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    throw Error(dir.string() + ": no such folder (create keys with 'lumistage keys init')");
  }
  if (const std::string problem = keyPermissionProblem(dir); !problem.empty())
    spdlog::warn("{}", problem);
  for (const fs::directory_entry& entry : fs::directory_iterator(dir)) {
    if (entry.path().extension() != ".pub") continue;
    nodes.push_back({entry.path().stem().string(), loadPublicKey(entry.path())});
  }
  std::sort(nodes.begin(), nodes.end(),
            [](const AuthorizedNode& a, const AuthorizedNode& b) { return a.name < b.name; });
  return nodes;
}

}  // namespace lumistage
