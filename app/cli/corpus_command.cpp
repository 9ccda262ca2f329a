#include "app/cli/corpus_command.h"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <memory>

#include "app/cli/checks.h"
#include "app/cli/progress.h"
#include "core/base/atomic_file.h"
#include "core/base/error.h"
#include "core/base/output_path.h"
#include "core/body/human_model.h"
#include "core/eval/corpus_eval.h"

namespace lumistage {

namespace {

namespace fs = std::filesystem;

// "A-B" as two numbers (A alone: A A). Throws Error naming `what` and `text`.
std::pair<int64_t, int64_t> parseRange(const std::string& text, const std::string& what) {
  const auto fail = [&] {
    throw Error(fmt::format("{} '{}': expected a number or a range FIRST-LAST", what, text));
  };
  const auto parse = [&](const std::string& part) -> int64_t {
    if (part.empty() || part.size() > 10 ||
        !std::all_of(part.begin(), part.end(), [](char c) { return c >= '0' && c <= '9'; }))
      fail();
    return std::stoll(part);
  };
  const size_t dash = text.find('-');
  if (dash == std::string::npos) {
    const int64_t v = parse(text);
    return {v, v};
  }
  const int64_t a = parse(text.substr(0, dash)), b = parse(text.substr(dash + 1));
  if (b < a) fail();
  return {a, b};
}

}  // namespace

std::vector<uint32_t> parseSeeds(const std::string& text) {
  std::vector<uint32_t> seeds;
  size_t begin = 0;
  while (begin <= text.size()) {
    const size_t comma = std::min(text.find(',', begin), text.size());
    const auto [a, b] = parseRange(text.substr(begin, comma - begin), "--seeds");
    if (b > 0xffffffffLL || b - a > 100000)
      throw Error(
          fmt::format("--seeds '{}': expected seeds below 2^32, at most 100000 of them", text));
    for (int64_t s = a; s <= b; ++s)
      if (std::find(seeds.begin(), seeds.end(), uint32_t(s)) == seeds.end())
        seeds.push_back(uint32_t(s));
    begin = comma + 1;
  }
  return seeds;
}

void addStageDrawOptions(CLI::App& command, StageDrawOptions& options) {
  command
      .add_option_function<std::string>(
          "--cameras",
          [&options](const std::string& text) {
            const auto [a, b] = parseRange(text, "--cameras");
            if (a < 2 || b > 64) throw Error("--cameras '" + text + "': expected 2 to 64 cameras");
            options.min_cameras = int(a);
            options.max_cameras = int(b);
          },
          "how many cameras a drawn rig has, MIN-MAX")
      ->default_str(fmt::format("{}-{}", options.min_cameras, options.max_cameras));
  command.add_option_function<std::string>(
      "--motions",
      [&options](const std::string& folder) {
        try {
          options.bvh_files = bvhFilesIn(folder);
        } catch (const Error& e) {
          throw Error(std::string("--motions ") + e.what());
        }
      },
      "also draw the motion from the BVH files in this folder (e.g. "
      "../shared/realdata/motions); the built-in clips are always drawn from");
  command
      .add_option_function<std::string>(
          "--start", [&options](const std::string& start) { options.any_start = start == "any"; },
          "where the motion starts: any (a random time of its clip) or clip (its first frame: "
          "the built-in clips' T-pose)")
      ->check(CLI::IsMember({"any", "clip"}))
      ->default_str("any");
}

void addCorpusCommand(CLI::App& app) {
  struct Args {
    std::string seeds, out, json;
    StageDrawOptions draw;
    BodyChoice body;
  };
  auto args = std::make_shared<Args>();
  CLI::App* corpus = app.add_subcommand(
      "corpus",
      "film randomised virtual stages (one a seed: rig, actor, motion, look) and measure motion "
      "capture on each: every stage's figures and the corpus's mean and worst");
  corpus
      ->add_option("--seeds", args->seeds,
                   "the stages, e.g. 1-20 (the development set) or 1000-1019 (held out: never tune "
                   "on them)")
      ->required();
  corpus
      ->add_option("-o,--out", args->out,
                   "folder of the filmed stages (seed-N/, each a session): kept, and reused by "
                   "the next run with the same stages")
      ->required();
  corpus->add_option("--frames", args->draw.frames, "frames a stage")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  corpus->add_option("--json", args->json, "write every stage's figures and the summary as JSON");
  addStageDrawOptions(*corpus, args->draw);
  addBodyOption(*corpus, args->body);
  corpus->callback([args] {
    const std::vector<uint32_t> seeds = parseSeeds(args->seeds);
    refuseOutputOverInputs("--json", args->json, {{"--out", args->out}});
    requireOutputFolder("--json", args->json);
    std::error_code ec;
    fs::create_directories(args->out, ec);
    if (ec) throw Error("--out " + args->out + ": cannot create: " + ec.message());
    const SkinnedMesh generic = loadBody(args->body);
    std::vector<CorpusStageResult> results;
    for (const uint32_t seed : seeds) {
      const std::string label = fmt::format("stage {}", seed);
      const CorpusStageResult r = evaluateCorpusStage(
          seed, args->draw, fs::path(args->out) / fmt::format("seed-{}", seed), generic, {},
          [&](int done, int total) { printProgress(label.c_str(), done, total); });
      fmt::print(
          "seed {}: {}/{} frames tracked, MPJPE {:.1f} mm (worst {:.1f}), height {:+.1f} "
          "cm: {}\n",
          seed, r.frames_tracked, r.frames, r.mpjpe_mm, r.mpjpe_mm_max, 100 * r.heightErrorM(),
          r.description);
      std::fflush(stdout);
      results.push_back(r);
    }
    fmt::print("\n{}", corpusTable(results));
    if (!args->json.empty()) writeFileAtomically(args->json, corpusJson(results));
  });
}

}  // namespace lumistage
