#include "app/cli/key_commands.h"

#include <fmt/format.h>

#include <memory>
#include <string>
#include <vector>

#include "core/net/curve_keys.h"

namespace lumistage {

namespace {

void printNextSteps(const KeyStore& store) {
  fmt::print(
      "On each node's PC, make a key folder holding nodes/<node>.key and studio.pub from {} (and "
      "nothing else: studio.key holds the studio's secret); the studio reads studio.key and "
      "authorized/.\n",
      store.dir().string());
}

}  // namespace

void addKeyCommands(CLI::App& app) {
  CLI::App* keys =
      app.add_subcommand("keys", "Create the CURVE keys that encrypt and admit studio traffic");
  keys->require_subcommand(1);

  struct InitArgs {
    std::string dir = "keys";
    std::vector<std::string> nodes;
    bool replace = false;
  };
  auto init_args = std::make_shared<InitArgs>();
  CLI::App* init = keys->add_subcommand(
      "init", "Create the studio key and a key per node, and authorize the nodes");
  init->add_option("--dir", init_args->dir, "key folder")->capture_default_str();
  init->add_option("--nodes", init_args->nodes, "node names, comma-separated (node1,node2,...)")
      ->delimiter(',');
  init->add_flag("--replace", init_args->replace,
                 "replace an existing studio key (every node must then get its files again)");
  init->callback([init_args] {
    KeyStore store(init_args->dir);
    store.init(init_args->nodes, init_args->replace);
    fmt::print("wrote {} and keys for {} node(s)\n", store.studioKeyPath().string(),
               init_args->nodes.size());
    printNextSteps(store);
  });

  struct AddArgs {
    std::string dir = "keys";
    std::string name;
  };
  auto add_args = std::make_shared<AddArgs>();
  CLI::App* add = keys->add_subcommand("add-node", "Create and authorize one more node's key");
  add->add_option("name", add_args->name, "node name (letters, digits, '-', '_')")->required();
  add->add_option("--dir", add_args->dir, "key folder")->capture_default_str();
  add->callback([add_args] {
    KeyStore store(add_args->dir);
    store.addNode(add_args->name);
    fmt::print("wrote {} and {}\n", store.nodeKeyPath(add_args->name).string(),
               store.authorizedPath(add_args->name).string());
    printNextSteps(store);
  });
}

}  // namespace lumistage
