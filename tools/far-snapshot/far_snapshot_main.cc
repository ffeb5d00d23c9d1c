// far-snapshot: a picture of one step of a scene, its PCS and contact triangles coloured,
// written as PNG. The step runs in this process through far::Pipeline on a GL context of its
// own (README.md, "Pictures", says why not through the daemon), and the picture is drawn with
// that same context (far::RenderSnapshot). Its own program, so that far-client links no GL.
// Usage: far-snapshot --help.
#include <cstdio>
#include <map>
#include <memory>

#include "cli_common.h"
#include "object_listing.h"
#include "step_flags.h"

#include "far/gpu/gl_context.h"
#include "far/gpu/snapshot_renderer.h"
#include "far/io/png_io.h"
#include "far/io/scene_io.h"
#include "far/pipeline/pipeline.h"

namespace far::cli {
namespace {

struct SnapshotFlags {
  std::string scene, png, gl_platform = "auto";
  int frame = 0, width = 1024, height = 768;
  StepFlags step;
};

// One mark per triangle of every object: the deepest thing the step found for it.
std::vector<SnapshotObject> MarkedObjects(const std::vector<SceneObject>& objects,
                                          const StepResult& result) {
  std::map<uint32_t, size_t> index;
  std::vector<SnapshotObject> marked;
  for (const SceneObject& object : objects) {
    index[object.id] = marked.size();
    marked.push_back(
        {&object.mesh, object.X_WO,
         std::vector<TriangleMark>(object.mesh.triangles.size(), TriangleMark::kPlain)});
  }
  const auto mark = [&](uint32_t id, uint32_t triangle, TriangleMark what) {
    const auto it = index.find(id);
    if (it == index.end()) return;
    std::vector<TriangleMark>& marks = marked[it->second].marks;
    if (triangle < marks.size()) marks[triangle] = std::max(marks[triangle], what);
  };
  for (const auto& [id, triangles] : result.pcs_primitives) {
    for (uint32_t t : triangles) mark(id, t, TriangleMark::kPcs);
  }
  for (const DistancePair& d : result.distance_pairs) {
    mark(d.pair.object_a, d.pair.triangle_a, TriangleMark::kNear);
    mark(d.pair.object_b, d.pair.triangle_b, TriangleMark::kNear);
  }
  for (const ContactPair& c : result.contacts) {
    mark(c.object_a, c.triangle_a, TriangleMark::kContact);
    mark(c.object_b, c.triangle_b, TriangleMark::kContact);
  }
  return marked;
}

// Runs the step on `objects` with a pipeline on the context current on this thread.
Result<StepResult> RunStep(const std::vector<SceneObject>& objects, const StepRequest& request) {
  PipelineOptions options;
  options.use_current_context = true;
  auto pipeline = Pipeline::Create(options);
  if (!pipeline) return pipeline.error();
  Scene scene;
  scene.objects = objects;
  if (auto ok = (*pipeline)->LoadScene(scene); !ok) return ok.error();
  return (*pipeline)->Step(request);
}

void PrintSummary(const SnapshotFlags& flags, const std::vector<SceneObject>& objects,
                  const StepResult& result, const std::string& renderer) {
  size_t pcs_triangles = 0;
  for (const auto& [id, triangles] : result.pcs_primitives) pcs_triangles += triangles.size();
  std::printf(
      "frame %d of %s: %zu objects; method %s on %s: pcs %zu objects, %zu triangles; %zu "
      "contact pairs; %zu distance pairs\n",
      flags.frame, flags.scene.c_str(), objects.size(), result.stats.method.c_str(),
      renderer.c_str(), result.pcs_objects.size(), pcs_triangles, result.contacts.size(),
      result.distance_pairs.size());
  const SceneObjects names(objects);
  for (const ObjectContact& contact : GroupByObjectPair(result.contacts, names))
    std::printf("      %s\n", Describe(contact, names).c_str());
}

int RunSnapshot(const SnapshotFlags& flags, GlPlatform platform) {
  auto request = flags.step.Request();
  if (!request) return Fail(request.error());
  auto scene = ReadScene(flags.scene);
  if (!scene) return Fail(scene.error());
  auto objects = ObjectsAtStep(*scene, static_cast<size_t>(flags.frame));
  if (!objects) {
    return Fail(MakeError(objects.error().code, "--frame: " + objects.error().message));
  }
  // A PNG that cannot be written is said before the step and the drawing, not after.
  if (auto ok = CheckWritableFile("--png", flags.png); !ok) return Fail(ok.error());
  auto context = GlContext::Create(platform);
  if (!context) return Fail(context.error());
  auto result = RunStep(*objects, *request);
  if (!result) return Fail(result.error());
  SnapshotOptions options;
  options.width = flags.width;
  options.height = flags.height;
  const std::vector<SnapshotObject> marked = MarkedObjects(*objects, *result);
  auto image = RenderSnapshot(marked, options);
  if (!image) return Fail(image.error());
  if (auto ok = WritePng(flags.png, image->width, image->height, image->rgb); !ok) {
    return Fail(ok.error());
  }
  PrintSummary(flags, *objects, *result, (*context)->renderer());
  std::printf(
      "wrote %s (%dx%d): objects grey, PCS triangles yellow, distance-pair triangles "
      "orange, contact triangles red (hidden ones drawn faded through what hides them)\n",
      flags.png.c_str(), image->width, image->height);
  return 0;
}

// The flags of far-snapshot, added to `app`.
void AddFlags(CLI::App& app, SnapshotFlags& flags) {
  app.add_option("scene", flags.scene, "far-scene/1 JSON file")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--png", flags.png, "PNG file to write")->required();
  app.add_option("--frame", flags.frame,
                 "the scene at this step, as far-client play numbers them (0: as loaded; k: "
                 "after frames[0..k-1])")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--width", flags.width, "picture width in pixels (16..8192)")
      ->capture_default_str();
  app.add_option("--height", flags.height, "picture height in pixels (16..8192)")
      ->capture_default_str();
  app.add_option("--gl-platform", flags.gl_platform, "EGL platform: " + GlPlatformNames())
      ->check([](const std::string& name) {
        return ParseGlPlatform(name)
                   ? std::string()
                   : "unknown platform '" + name + "' (" + GlPlatformNames() + ")";
      })
      ->capture_default_str();
  flags.step.Add(&app);
}

}  // namespace
}  // namespace far::cli

int main(int argc, char** argv) {
  far::cli::SetProgramName("far-snapshot");
  return far::cli::RunGuarded([&] {
    CLI::App app{
        "far-snapshot: draw one step of a scene as a PNG picture: objects grey, PCS triangles\n"
        "yellow, contact triangles red. Runs the step in this process (far::Pipeline on its own\n"
        "headless GL context, as the daemon would), no daemon needed; prints the contacts by\n"
        "object pair",
        "far-snapshot"};
    far::cli::SnapshotFlags flags;
    far::cli::AddFlags(app, flags);
    if (auto done = far::cli::ParseCommandLine(app, std::vector<std::string>(argv, argv + argc)))
      return *done;
    return far::cli::RunSnapshot(flags, *far::ParseGlPlatform(flags.gl_platform));
  });
}
