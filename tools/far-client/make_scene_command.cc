// far-client make-scene: one of far::scenes' generated scenes, written as far-scene/1.
#include <filesystem>

#include "cli_common.h"
#include "commands.h"

#include "far/io/mesh_io.h"
#include "far/io/scene_io.h"
#include "far/scenes/scenes.h"

namespace far::cli {
namespace {

// The flags of make-scene; the scene is written with its meshes next to it.
struct MakeSceneFlags {
  std::string out, kind = "demo", mesh;
  int frames = 30, leaves = 0, cells = 0, triangles = 100000, subdivision = 5;
  uint64_t seed = 7;
  CLI::App* command = nullptr;

  void Add(CLI::App* app) {
    command = app->add_subcommand(
        "make-scene",
        "Write a generated animated scene (far-scene/1 with frames; meshes next to it). Kinds:\n"
        "  demo      a static tree, falling deformable leaves and a vase that breaks (small)\n"
        "  leaves    the paper's falling leaves: a static tree and 150 deformable leaves that "
        "hang,\n            sway, fall and bend (vertices every frame); 42,304 triangles\n"
        "  breaking  a 100K-triangle static terrain and a 35K-triangle rigid vase that rolls "
        "into a rock\n            and breaks into 12 fragments mid-run (removal and "
        "additions, then poses)\n"
        "  bunnies   two Stanford bunnies refined to 91,850 triangles each (--subdivision 5), "
        "one static,\n            one moving rigidly through it (poses)\n"
        "  scaling   spheres (rigid), cloths (deformable) and ground (static) totalling "
        "--triangles,\n            the same mix at every size (5K to 300K), for time-vs-size "
        "curves");
    command->add_option("out", out, "scene JSON path to write (meshes go next to it)")->required();
    command->add_option("--kind", kind, "demo, leaves, breaking, bunnies or scaling")
        ->check(CLI::IsMember({"demo", "leaves", "breaking", "bunnies", "scaling"}))
        ->capture_default_str();
    command->add_option("--frames", frames, "animation frames, frame 0 included")
        ->check(CLI::Range(1, 100000))
        ->capture_default_str();
    command->add_option("--seed", seed, "random seed (same seed, same scene)")
        ->capture_default_str();
    command->add_option("--leaves", leaves, "demo, leaves: number of leaves (default 40, 150)")
        ->check(CLI::Range(0, 100000));
    command
        ->add_option("--cells", cells,
                     "demo, leaves: leaf grid cells per side, 2 cells^2 triangles (default 2, 8)")
        ->check(CLI::Range(1, 1000));
    command->add_option("--triangles", triangles, "scaling: target total triangles")
        ->check(CLI::Range(1000, 50000000))
        ->capture_default_str();
    command->add_option("--mesh", mesh,
                        "bunnies: the bunny mesh (default: share/far/data/bunny.obj next to "
                        "far-client's bin/, then the source tree's bench/data/bunny.obj)");
    command
        ->add_option("--subdivision", subdivision,
                     "bunnies: split each edge in n (n^2 triangles per triangle)")
        ->check(CLI::Range(1, 64))
        ->capture_default_str();
  }
};

// The bunny for `make-scene --kind bunnies`: --mesh, else the installed copy, else the source
// tree's (a build that was never installed).
far::Result<far::Mesh> ReadBunny(const std::string& mesh) {
  if (!mesh.empty()) return far::ReadMesh(mesh);
  std::vector<std::filesystem::path> tried;
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (!ec) tried.push_back(exe.parent_path() / ".." / "share" / "far" / "data" / "bunny.obj");
  tried.emplace_back(FAR_SOURCE_BUNNY_OBJ);
  std::string places;
  for (const std::filesystem::path& path : tried) {
    if (std::filesystem::exists(path, ec)) return far::ReadMesh(path.lexically_normal());
    places += (places.empty() ? "" : ", ") + path.lexically_normal().string();
  }
  return far::MakeError(far::ErrorCode::kNotFound,
                        "no bunny mesh: tried " + places + "; pass one with --mesh PATH");
}

// Makes the scene file's folder and checks that the file can be written, before the scene is
// generated (seconds for the large kinds).
Result<void> PrepareOutput(const std::string& out) {
  std::error_code ec;
  const std::filesystem::path folder = std::filesystem::absolute(out, ec).parent_path();
  if (!ec) std::filesystem::create_directories(folder, ec);
  if (ec) {
    return MakeError(ErrorCode::kIoError,
                     out + ": cannot make its folder " + folder.string() + ": " + ec.message());
  }
  return CheckWritableFile("", out);
}

int MakeScene(const MakeSceneFlags& flags) {
  const auto given = [&](const char* option) { return flags.command->count(option) > 0; };
  const bool leaf_kind = flags.kind == "demo" || flags.kind == "leaves";
  for (const char* option : {"--leaves", "--cells"}) {
    if (!leaf_kind && given(option)) {
      std::fprintf(stderr, "far-client: %s applies to --kind demo or leaves only\n", option);
      return kExitFailure;
    }
  }
  if (auto ok = PrepareOutput(flags.out); !ok) return Fail(ok.error());
  const auto t0 = Clock::now();
  far::Scene scene;
  if (flags.kind == "demo") {
    scene = far::scenes::AnimatedLeavesScene(flags.seed, given("--leaves") ? flags.leaves : 40,
                                             given("--cells") ? flags.cells : 2, flags.frames);
  } else if (flags.kind == "leaves") {
    scene = far::scenes::PaperLeavesScene(flags.seed, flags.frames,
                                          given("--leaves") ? flags.leaves : 150,
                                          given("--cells") ? flags.cells : 8);
  } else if (flags.kind == "breaking") {
    scene = far::scenes::BreakingScene(flags.seed, flags.frames);
  } else if (flags.kind == "bunnies") {
    auto bunny = ReadBunny(flags.mesh);
    if (!bunny) return Fail(bunny.error());
    scene = far::scenes::BunniesScene(*bunny, flags.subdivision, flags.seed, flags.frames);
  } else {
    scene = far::scenes::ScalingScene(flags.seed, flags.triangles, flags.frames);
  }
  const double generated_s = std::chrono::duration<double>(Clock::now() - t0).count();
  int64_t triangles = 0;
  for (const far::SceneObject& object : scene.objects) triangles += object.mesh.num_triangles();
  if (auto ok = far::WriteScene(scene, flags.out); !ok) return Fail(ok.error());
  std::printf(
      "wrote %s (%s): %zu objects and %lld triangles at frame 0, %zu frames (%zu "
      "updates); generated in %.2f s\n",
      flags.out.c_str(), flags.kind.c_str(), scene.objects.size(),
      static_cast<long long>(triangles), scene.frames.size() + 1, scene.frames.size(), generated_s);
  return 0;
}

}  // namespace

Command AddMakeSceneCommand(CLI::App& app) {
  auto flags = std::make_shared<MakeSceneFlags>();
  flags->Add(&app);
  return {flags->command, [flags] { return MakeScene(*flags); }};
}

}  // namespace far::cli
