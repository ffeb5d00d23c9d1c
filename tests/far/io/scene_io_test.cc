#include "far/io/scene_io.h"

#include <cmath>
#include <string>

#include "io_test_util.h"
#include <gtest/gtest.h>

#include "far/base/limits.h"
#include "far/io/mesh_io.h"

namespace far {
namespace {

using testing::IsError;
using testing::ReadFile;
using testing::SameMesh;
using testing::TempDir;
using testing::WriteFile;

constexpr const char* kTriangleObj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
constexpr const char* kTriangleMovedObj = "v 0 0 1\nv 1 0 1\nv 0 1 1\nf 1 2 3\n";
constexpr const char* kQuadObj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";

// A folder with tri.obj, tri_t1.obj (same triangles, moved), quad.obj and sub/quad.ply.
class SceneIoTest : public ::testing::Test {
 protected:
  void SetUp() override {
    WriteFile(dir_ / "tri.obj", kTriangleObj);
    WriteFile(dir_ / "tri_t1.obj", kTriangleMovedObj);
    WriteFile(dir_ / "quad.obj", kQuadObj);
    const Result<Mesh> quad = ReadObj(kQuadObj, "quad.obj");
    ASSERT_TRUE(quad.ok());
    std::filesystem::create_directories(dir_ / "sub");
    ASSERT_TRUE(WritePly(*quad, dir_ / "sub" / "quad.ply").ok());
  }

  Result<Scene> Parse(const std::string& json) { return ParseScene(json, dir_.path()); }

  // A scene JSON with `objects` (the text of the array's items) and optional `frames`.
  static std::string SceneJson(const std::string& objects, const std::string& frames = "") {
    std::string json = R"({"format": "far-scene/1", "objects": [)" + objects + "]";
    if (!frames.empty()) json += R"(, "frames": [)" + frames + "]";
    return json + "}";
  }

  TempDir dir_;
};

constexpr const char* kRigid = R"({"id": 1, "mesh": "tri.obj", "motion": "rigid"})";
constexpr const char* kStatic = R"({"id": 2, "mesh": "quad.obj", "motion": "static"})";
constexpr const char* kDeformable = R"({"id": 3, "mesh": "tri.obj", "motion": "deformable"})";

TEST_F(SceneIoTest, ParsesObjectsWithDefaultPose) {
  const Result<Scene> scene = Parse(SceneJson(std::string(kRigid) + ", " + kStatic));
  ASSERT_TRUE(scene.ok()) << ToString(scene.error());
  ASSERT_EQ(scene->objects.size(), 2u);
  const SceneObject& rigid = scene->objects[0];
  EXPECT_EQ(rigid.id, 1u);
  EXPECT_EQ(rigid.mesh_path, "tri.obj");
  EXPECT_EQ(rigid.motion, Motion::kRigid);
  EXPECT_EQ(rigid.mesh.num_triangles(), 1);
  EXPECT_TRUE(rigid.X_WO.ToIsometry().isApprox(Eigen::Isometry3d::Identity()));
  EXPECT_EQ(scene->objects[1].motion, Motion::kStatic);
  EXPECT_EQ(scene->objects[1].mesh.num_triangles(), 2);
  EXPECT_TRUE(scene->frames.empty());
}

TEST_F(SceneIoTest, ParsesPosesAndNormalizesNearlyUnitQuaternions) {
  const double s = std::sqrt(0.5) * (1 + 4e-7);  // norm 1 + 4e-7: accepted, then normalized
  const std::string object = R"({"id": 9, "mesh": "tri.obj", "motion": "rigid", "pose": )"
                             R"({"translation": [1, 2.5, -3], "rotation_wxyz": [)" +
                             std::to_string(s) + ", 0, 0, " + std::to_string(s) + "]}}";
  const Result<Scene> scene = Parse(SceneJson(object));
  ASSERT_TRUE(scene.ok()) << ToString(scene.error());
  const Pose& X_WO = scene->objects[0].X_WO;
  EXPECT_EQ(X_WO.translation, Eigen::Vector3d(1, 2.5, -3));
  EXPECT_NEAR(X_WO.rotation.norm(), 1.0, 1e-15);
  // 90 degrees about z, then the translation.
  const Eigen::Vector3d p_WQ = X_WO.ToIsometry() * Eigen::Vector3d(1, 0, 0);
  EXPECT_TRUE(p_WQ.isApprox(Eigen::Vector3d(1, 3.5, -3), 1e-12)) << p_WQ.transpose();
}

TEST_F(SceneIoTest, PoseFieldsAreOptionalEachDefaultingToIdentity) {
  const Result<Scene> scene = Parse(SceneJson(
      R"({"id": 1, "mesh": "tri.obj", "motion": "rigid", "pose": {"translation": [0, 0, 5]}},)"
      R"({"id": 2, "mesh": "tri.obj", "motion": "rigid", "pose": {"rotation_wxyz": [0, 1, 0, 0]}})"));
  ASSERT_TRUE(scene.ok()) << ToString(scene.error());
  EXPECT_TRUE(scene->objects[0].X_WO.rotation.isApprox(Eigen::Quaterniond::Identity()));
  EXPECT_EQ(scene->objects[1].X_WO.translation, Eigen::Vector3d::Zero());
  EXPECT_EQ(scene->objects[1].X_WO.rotation.x(), 1.0);
}

TEST_F(SceneIoTest, ResolvesMeshPathsAgainstBaseDir) {
  const Result<Scene> scene =
      Parse(SceneJson(R"({"id": 4, "mesh": "sub/quad.ply", "motion": "static"},)"
                      R"({"id": 5, "mesh": "sub/../quad.obj", "motion": "static"})"));
  ASSERT_TRUE(scene.ok()) << ToString(scene.error());
  EXPECT_EQ(scene->objects[0].mesh_path, "sub/quad.ply");
  EXPECT_TRUE(SameMesh(scene->objects[0].mesh, scene->objects[1].mesh));
  // A scene file in sub/ reaches its parent folder with "..".
  WriteFile(dir_ / "sub" / "scene.json",
            SceneJson(R"({"id": 1, "mesh": "../tri.obj", "motion": "static"})"));
  const Result<Scene> nested = ReadScene(dir_ / "sub" / "scene.json");
  ASSERT_TRUE(nested.ok()) << ToString(nested.error());
  EXPECT_EQ(nested->objects[0].mesh.num_vertices(), 3);
}

TEST_F(SceneIoTest, CommentsAreAllowedAtEveryLevel) {
  const Result<Scene> scene =
      Parse(R"({"format": "far-scene/1", "comment": "hello", "objects": [)"
            R"({"id": 1, "mesh": "tri.obj", "motion": "deformable", "comment": "a",)"
            R"( "pose": {"translation": [0, 0, 0], "comment": "b"}}],)"
            R"( "frames": [{"comment": "c", "poses": [{"id": 1, "comment": "d"}],)"
            R"( "vertices": [{"id": 1, "mesh": "tri_t1.obj", "comment": "e"}]}]})");
  ASSERT_TRUE(scene.ok()) << ToString(scene.error());
  EXPECT_EQ(scene->frames.size(), 1u);
  EXPECT_TRUE(IsError(Parse(R"({"format": "far-scene/1", "comment": 3, "objects": []})"),
                      ErrorCode::kParseError, "comment: expected a string, got number"));
}

// A misspelt key would otherwise be skipped and its value replaced by a default (a
// "translaton" puts the object at the origin): every level names the key, its JSON path and
// the key that was most likely meant.
TEST_F(SceneIoTest, UnknownKeysAreErrorsNamingPathAndClosestKey) {
  struct Case {
    std::string json, message;
  };
  const std::string frame_objects = std::string(kRigid) + ", " + kDeformable;
  const std::vector<Case> cases = {
      {R"({"format": "far-scene/1", "objets": []})",
       "objets: unknown key 'objets'; did you mean 'objects'? (keys of the top level: format, "
       "objects, frames, comment)"},
      {SceneJson(R"({"id": 1, "mesh": "tri.obj", "motion": "rigid", "pose": )"
                 R"({"translaton": [0, 0, 5]}})"),
       "objects[0].pose.translaton: unknown key 'translaton'; did you mean 'translation'?"},
      {SceneJson(R"({"id": 1, "mesh": "tri.obj", "motion": "rigid", "pose": )"
                 R"({"rotation": [1, 0, 0, 0]}})"),
       "objects[0].pose.rotation: unknown key 'rotation'; did you mean 'rotation_wxyz'?"},
      {SceneJson(R"({"id": 1, "mesh": "tri.obj", "motoin": "rigid"})"),
       "objects[0].motoin: unknown key 'motoin'; did you mean 'motion'?"},
      {SceneJson(R"({"id": 1, "mesh": "tri.obj", "motion": "rigid", "color": [1, 0, 0]})"),
       "objects[0].color: unknown key 'color' (keys of an object: id, name, mesh, motion, pose, "
       "comment)"},
      {SceneJson(frame_objects, R"({"pose": [{"id": 1}]})"),
       "frames[0].pose: unknown key 'pose'; did you mean 'poses'?"},
      {SceneJson(frame_objects, R"({"add": [{"id": 5, "mesh": "tri.obj", "motion": "rigid",)"
                                R"( "pose": {"translation": [0, 0, 1], "scael": 2}}]})"),
       "frames[0].add[0].pose.scael: unknown key 'scael' (keys of a pose: translation, "
       "rotation_wxyz, comment)"},
      {SceneJson(frame_objects, R"({}, {"poses": [{"id": 1, "translatoin": [0, 0, 1]}]})"),
       "frames[1].poses[0].translatoin: unknown key 'translatoin'; did you mean 'translation'?"},
      {SceneJson(frame_objects, R"({"vertices": [{"id": 3, "mehs": "tri_t1.obj"}]})"),
       "frames[0].vertices[0].mehs: unknown key 'mehs'; did you mean 'mesh'?"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.json);
    EXPECT_TRUE(IsError(Parse(c.json), ErrorCode::kParseError, c.message));
  }
  // Unprintable keys are shown safely.
  EXPECT_TRUE(IsError(Parse("{\"format\": \"far-scene/1\", \"objects\": [], \"\\u0001x\": 1}"),
                      ErrorCode::kParseError, "?x: unknown key '?x'"));
  // Another version's keys are not judged by this version's list: the version is the error.
  EXPECT_TRUE(IsError(Parse(R"({"format": "far-scene/2", "objects": [], "lights": []})"),
                      ErrorCode::kVersionMismatch, "unsupported version"));
}

TEST_F(SceneIoTest, NamesAreReadCheckedAndWrittenBack) {
  const Result<Scene> scene = Parse(SceneJson(
      R"({"id": 1, "name": "leaf-1", "mesh": "tri.obj", "motion": "rigid"}, )"
      R"({"id": 2, "mesh": "quad.obj", "motion": "static"})",
      R"({"add": [{"id": 3, "name": "Blatt \u00fcber", "mesh": "tri.obj", "motion": "rigid"}]})"));
  ASSERT_TRUE(scene.ok()) << ToString(scene.error());
  EXPECT_EQ(scene->objects[0].name, "leaf-1");
  EXPECT_EQ(scene->objects[1].name, "");
  EXPECT_EQ(scene->frames[0].additions[0].name,
            "Blatt \xc3\xbc"
            "ber");
  TempDir out;
  ASSERT_TRUE(WriteScene(*scene, out / "s.json").ok());
  const Result<Scene> again = ReadScene(out / "s.json");
  ASSERT_TRUE(again.ok()) << ToString(again.error());
  EXPECT_EQ(again->objects[0].name, "leaf-1");
  EXPECT_EQ(again->objects[1].name, "");
  EXPECT_EQ(again->frames[0].additions[0].name, scene->frames[0].additions[0].name);
  EXPECT_EQ(ReadFile(out / "s.json").find("\"name\": \"\""), std::string::npos)
      << "an object without a name is written without the key";

  EXPECT_TRUE(
      IsError(Parse(SceneJson(R"({"id": 1, "name": 7, "mesh": "tri.obj", "motion": "rigid"})")),
              ErrorCode::kParseError, "objects[0].name: expected a string, got number"));
  EXPECT_TRUE(IsError(
      Parse(SceneJson(R"({"id": 1, "name": "a\nb", "mesh": "tri.obj", "motion": "rigid"})")),
      ErrorCode::kInvalidArgument, "objects[0].name: control character (byte 10)"));
  const std::string long_name(kMaxObjectNameBytes + 1, 'x');
  EXPECT_TRUE(IsError(Parse(SceneJson(R"({"id": 1, "name": ")" + long_name +
                                      R"(", "mesh": "tri.obj", "motion": "rigid"})")),
                      ErrorCode::kInvalidArgument, "objects[0].name: longer than 100 bytes"));
}

TEST_F(SceneIoTest, ParsesFrames) {
  const Result<Scene> scene = Parse(SceneJson(
      std::string(kRigid) + ", " + kStatic + ", " + kDeformable,
      R"({"poses": [{"id": 1, "translation": [0, 0, 1]}, {"id": 3, "rotation_wxyz": [0, 0, 0, 1]}],)"
      R"( "vertices": [{"id": 3, "mesh": "tri_t1.obj"}]},)"
      R"({"remove": [2], "add": [{"id": 2, "mesh": "tri.obj", "motion": "rigid"}]},)"
      R"({},)"
      R"({"poses": [{"id": 2, "translation": [5, 0, 0]}], "remove": [1]})"));
  ASSERT_TRUE(scene.ok()) << ToString(scene.error());
  ASSERT_EQ(scene->frames.size(), 4u);
  const FrameUpdate& first = scene->frames[0];
  ASSERT_EQ(first.poses.size(), 2u);
  EXPECT_EQ(first.poses[0].first, 1u);
  EXPECT_EQ(first.poses[0].second.translation, Eigen::Vector3d(0, 0, 1));
  EXPECT_EQ(first.poses[1].second.rotation.z(), 1.0);
  ASSERT_EQ(first.vertices.size(), 1u);
  EXPECT_EQ(first.vertices[0].first, 3u);
  EXPECT_EQ(first.vertices[0].second.p_MV[0], Eigen::Vector3d(0, 0, 1));
  ASSERT_EQ(first.vertex_mesh_paths.size(), 1u);
  EXPECT_EQ(first.vertex_mesh_paths[0], "tri_t1.obj");
  EXPECT_EQ(scene->frames[1].removals, std::vector<uint32_t>{2});
  ASSERT_EQ(scene->frames[1].additions.size(), 1u);
  EXPECT_EQ(scene->frames[1].additions[0].motion, Motion::kRigid);
  EXPECT_TRUE(scene->frames[2].poses.empty());
}

TEST_F(SceneIoTest, ReadSceneReadsFromFile) {
  WriteFile(dir_ / "scene.json", SceneJson(kRigid));
  const Result<Scene> scene = ReadScene(dir_ / "scene.json");
  ASSERT_TRUE(scene.ok()) << ToString(scene.error());
  EXPECT_EQ(scene->objects[0].id, 1u);
}

TEST(SceneTest, MotionNamesRoundTrip) {
  for (const Motion motion : {Motion::kStatic, Motion::kRigid, Motion::kDeformable}) {
    EXPECT_EQ(ParseMotion(ToString(motion)), motion);
  }
  EXPECT_FALSE(ParseMotion("Static").has_value());
}

TEST(SceneTest, DefaultPoseIsIdentity) {
  const Pose pose;
  EXPECT_TRUE(pose.ToIsometry().isApprox(Eigen::Isometry3d::Identity()));
}

// The example of docs/scene-format.md, kept in tests/data so that the docs stay true.
TEST(SceneDocsTest, ExampleSceneReads) {
  const Result<Scene> scene =
      ReadScene(std::filesystem::path(FAR_TEST_DATA_DIR) / "scenes" / "example" / "scene.json");
  ASSERT_TRUE(scene.ok()) << ToString(scene.error());
  EXPECT_EQ(scene->objects.size(), 3u);
  EXPECT_EQ(scene->frames.size(), 2u);
  EXPECT_EQ(scene->objects[1].name, "box");
  EXPECT_EQ(scene->frames[1].additions[0].name, "chip");
}

// Round trips.

bool SamePose(const Pose& a, const Pose& b) {
  return a.translation == b.translation && a.rotation.coeffs().isApprox(b.rotation.coeffs(), 1e-15);
}

void ExpectSameObject(const SceneObject& a, const SceneObject& b) {
  EXPECT_EQ(a.id, b.id);
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.mesh_path, b.mesh_path);
  EXPECT_EQ(a.motion, b.motion);
  EXPECT_TRUE(SamePose(a.X_WO, b.X_WO));
  EXPECT_TRUE(SameMesh(a.mesh, b.mesh));
}

void ExpectSameScene(const Scene& a, const Scene& b) {
  ASSERT_EQ(a.objects.size(), b.objects.size());
  for (size_t i = 0; i < a.objects.size(); ++i) ExpectSameObject(a.objects[i], b.objects[i]);
  ASSERT_EQ(a.frames.size(), b.frames.size());
  for (size_t f = 0; f < a.frames.size(); ++f) {
    const FrameUpdate& fa = a.frames[f];
    const FrameUpdate& fb = b.frames[f];
    EXPECT_EQ(fa.removals, fb.removals);
    ASSERT_EQ(fa.additions.size(), fb.additions.size());
    for (size_t j = 0; j < fa.additions.size(); ++j)
      ExpectSameObject(fa.additions[j], fb.additions[j]);
    ASSERT_EQ(fa.poses.size(), fb.poses.size());
    for (size_t j = 0; j < fa.poses.size(); ++j) {
      EXPECT_EQ(fa.poses[j].first, fb.poses[j].first);
      EXPECT_TRUE(SamePose(fa.poses[j].second, fb.poses[j].second));
    }
    ASSERT_EQ(fa.vertices.size(), fb.vertices.size());
    for (size_t j = 0; j < fa.vertices.size(); ++j) {
      EXPECT_EQ(fa.vertices[j].first, fb.vertices[j].first);
      EXPECT_TRUE(SameMesh(fa.vertices[j].second, fb.vertices[j].second));
    }
  }
}

TEST_F(SceneIoTest, ReadWriteReadRoundTripWritesMissingMeshes) {
  const std::string json = SceneJson(
      std::string(R"({"id": 1, "mesh": "tri.obj", "motion": "rigid", "pose": )"
                  R"({"translation": [0.1, 0.2, 0.3], "rotation_wxyz": [0.5, 0.5, 0.5, 0.5]}},)") +
          kStatic + "," + kDeformable +
          R"(, {"id": 4, "mesh": "sub/quad.ply", "motion": "static"})",
      R"({"poses": [{"id": 1, "translation": [1e-300, -1e12, 0.1]}], "vertices": [{"id": 3, "mesh": "tri_t1.obj"}]},)"
      R"({"remove": [2], "add": [{"id": 7, "mesh": "sub/quad.ply", "motion": "rigid"}]})");
  WriteFile(dir_ / "scene.json", json);
  const Result<Scene> original = ReadScene(dir_ / "scene.json");
  ASSERT_TRUE(original.ok()) << ToString(original.error());

  TempDir out;
  ASSERT_TRUE(WriteScene(*original, out / "copy" / "scene.json").ok());
  for (const char* file : {"tri.obj", "quad.obj", "sub/quad.ply", "tri_t1.obj"}) {
    EXPECT_TRUE(std::filesystem::exists(out / "copy" / file)) << file;
  }
  const Result<Scene> copy = ReadScene(out / "copy" / "scene.json");
  ASSERT_TRUE(copy.ok()) << ToString(copy.error());
  ExpectSameScene(*original, *copy);
}

TEST_F(SceneIoTest, WritesInMemorySceneWithGeneratedVertexFileNames) {
  const Result<Mesh> triangle = ReadObj(kTriangleObj, "tri");
  const Result<Mesh> moved = ReadObj(kTriangleMovedObj, "moved");
  ASSERT_TRUE(triangle.ok() && moved.ok());
  Scene scene;
  scene.objects.push_back({5, "meshes/leaf.obj", *triangle, Motion::kDeformable, Pose{}});
  scene.objects.push_back({6, "meshes/leaf.stl", *triangle, Motion::kRigid, Pose{}});
  FrameUpdate frame;
  frame.vertices.emplace_back(5, *moved);
  Pose X_WO;
  X_WO.translation = Eigen::Vector3d(1, 2, 3);
  X_WO.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()));
  frame.poses.emplace_back(6, X_WO);
  scene.frames.push_back(frame);

  TempDir out;
  const Result<void> written = WriteScene(scene, out / "anim.json");
  ASSERT_TRUE(written.ok()) << ToString(written.error());
  EXPECT_TRUE(std::filesystem::exists(out / "anim_frame0_id5.obj"));
  EXPECT_TRUE(std::filesystem::exists(out / "meshes" / "leaf.stl"));
  const Result<Scene> read = ReadScene(out / "anim.json");
  ASSERT_TRUE(read.ok()) << ToString(read.error());
  EXPECT_EQ(read->frames[0].vertex_mesh_paths[0], "anim_frame0_id5.obj");
  // The STL mesh comes back with 3 vertices per triangle; everything else is exact.
  scene.objects[1].mesh = read->objects[1].mesh;
  ExpectSameScene(scene, *read);
}

TEST_F(SceneIoTest, WriteSceneKeepsExistingMeshFiles) {
  const Result<Scene> scene = Parse(SceneJson(kRigid));
  ASSERT_TRUE(scene.ok());
  WriteFile(dir_ / "out" / "tri.obj", "# hand-written, must survive\n" + std::string(kTriangleObj));
  ASSERT_TRUE(WriteScene(*scene, dir_ / "out" / "scene.json").ok());
  EXPECT_EQ(ReadFile(dir_ / "out" / "tri.obj").rfind("# hand-written", 0), 0u);
}

// Scene errors, one by one: code and message naming the JSON path.

TEST_F(SceneIoTest, ReportsMissingSceneFile) {
  EXPECT_TRUE(
      IsError(ReadScene(dir_ / "nope.json"), ErrorCode::kIoError, "nope.json: cannot open"));
}

TEST_F(SceneIoTest, ReportsJsonSyntaxErrorsWithByteOffset) {
  EXPECT_TRUE(IsError(Parse(R"({"format": "far-scene/1", "objects": [}})"), ErrorCode::kParseError,
                      "JSON syntax error at byte 38"));
  EXPECT_TRUE(IsError(Parse(""), ErrorCode::kParseError, "JSON syntax error at byte"));
  EXPECT_TRUE(IsError(Parse(R"({"format": "far-scene/1", "objects": []} trailing)"),
                      ErrorCode::kParseError, "JSON syntax error"));
  WriteFile(dir_ / "bad.json", "{");
  EXPECT_TRUE(IsError(ReadScene(dir_ / "bad.json"), ErrorCode::kParseError,
                      (dir_ / "bad.json").string() + ": JSON syntax error at byte 1"));
}

TEST_F(SceneIoTest, RejectsDuplicateJsonKeys) {
  EXPECT_TRUE(
      IsError(Parse(SceneJson(R"({"id": 1, "id": 2, "mesh": "tri.obj", "motion": "rigid"})")),
              ErrorCode::kParseError, "duplicate key \"id\""));
}

TEST_F(SceneIoTest, RejectsNumbersBeyondDouble) {
  EXPECT_TRUE(IsError(Parse(SceneJson(R"({"id": 1, "mesh": "tri.obj", "motion": "rigid",)"
                                      R"( "pose": {"translation": [1e999, 0, 0]}})")),
                      ErrorCode::kParseError, "number overflow"));
}

TEST_F(SceneIoTest, RejectsCoordinatesBeyondTheLimit) {
  // Doubles, but beyond far::kMaxCoordinate: refused as the pipeline and the ring refuse them.
  EXPECT_TRUE(IsError(Parse(SceneJson(R"({"id": 1, "mesh": "tri.obj", "motion": "rigid",)"
                                      R"( "pose": {"translation": [0, 1e300, 0]}})")),
                      ErrorCode::kInvalidArgument,
                      "objects[0].pose.translation: a coordinate beyond +-1e+12 (1e+300)"));
  EXPECT_TRUE(
      IsError(Parse(SceneJson(kRigid, R"({"poses": [{"id": 1, "translation": [2e12, 0, 0]}]})")),
              ErrorCode::kInvalidArgument, "a coordinate beyond +-1e+12 (2e+12)"));
}

TEST_F(SceneIoTest, SurvivesDeeplyNestedJson) {
  const int depth = 100000;
  const std::string nested = std::string(depth, '[') + std::string(depth, ']');
  // Parsed (and freed) without overflowing the stack; then refused for its unknown key.
  EXPECT_TRUE(IsError(Parse(R"({"format": "far-scene/1", "objects": [], "deep": )" + nested + "}"),
                      ErrorCode::kParseError, "deep: unknown key 'deep'"));
  EXPECT_TRUE(IsError(Parse(R"({"format": "far-scene/1", "objects": )" + nested + "}"),
                      ErrorCode::kParseError, "objects[0]: expected a JSON object, got array"));
}

TEST_F(SceneIoTest, RejectsNonObjectRoot) {
  EXPECT_TRUE(
      IsError(Parse("[]"), ErrorCode::kParseError, "(root): expected a JSON object, got array"));
}

TEST_F(SceneIoTest, RejectsMissingOrWrongFormat) {
  EXPECT_TRUE(IsError(Parse(R"({"objects": []})"), ErrorCode::kParseError, "format: missing"));
  EXPECT_TRUE(IsError(Parse(R"({"format": 1, "objects": []})"), ErrorCode::kParseError,
                      "format: expected a string, got number"));
  EXPECT_TRUE(IsError(Parse(R"({"format": "obj", "objects": []})"), ErrorCode::kParseError,
                      "format: expected \"far-scene/1\", got 'obj'"));
  EXPECT_TRUE(IsError(Parse(R"({"format": "far-scene/2", "objects": []})"),
                      ErrorCode::kVersionMismatch, "format: unsupported version \"far-scene/2\""));
}

TEST_F(SceneIoTest, RejectsMissingOrMistypedObjects) {
  EXPECT_TRUE(
      IsError(Parse(R"({"format": "far-scene/1"})"), ErrorCode::kParseError, "objects: missing"));
  EXPECT_TRUE(IsError(Parse(R"({"format": "far-scene/1", "objects": {}})"), ErrorCode::kParseError,
                      "objects: expected an array, got object"));
  EXPECT_TRUE(IsError(Parse(SceneJson(std::string(kRigid) + ", 5")), ErrorCode::kParseError,
                      "objects[1]: expected a JSON object, got number"));
}

TEST_F(SceneIoTest, RejectsMissingObjectFields) {
  EXPECT_TRUE(IsError(Parse(SceneJson(R"({"mesh": "tri.obj", "motion": "rigid"})")),
                      ErrorCode::kParseError, "objects[0].id: missing"));
  EXPECT_TRUE(IsError(Parse(SceneJson(R"({"id": 1, "motion": "rigid"})")), ErrorCode::kParseError,
                      "objects[0].mesh: missing"));
  EXPECT_TRUE(IsError(Parse(SceneJson(R"({"id": 1, "mesh": "tri.obj"})")), ErrorCode::kParseError,
                      "objects[0].motion: missing"));
}

TEST_F(SceneIoTest, RejectsIdsThatAreNotUint32) {
  for (const char* id : {"-1", "4294967296", "1.5", "1e3"}) {
    EXPECT_TRUE(IsError(Parse(SceneJson(std::string(R"({"id": )") + id +
                                        R"(, "mesh": "tri.obj", "motion": "rigid"})")),
                        ErrorCode::kInvalidArgument,
                        "objects[0].id: expected an unsigned 32-bit integer, got"))
        << id;
  }
  EXPECT_TRUE(IsError(Parse(SceneJson(R"({"id": "7", "mesh": "tri.obj", "motion": "rigid"})")),
                      ErrorCode::kParseError,
                      "objects[0].id: expected an unsigned 32-bit integer, got string"));
  const Result<Scene> max =
      Parse(SceneJson(R"({"id": 4294967295, "mesh": "tri.obj", "motion": "rigid"})"));
  ASSERT_TRUE(max.ok()) << ToString(max.error());
  EXPECT_EQ(max->objects[0].id, 4294967295u);
}

TEST_F(SceneIoTest, RejectsBadMeshPaths) {
  EXPECT_TRUE(IsError(Parse(SceneJson(R"({"id": 1, "mesh": 3, "motion": "rigid"})")),
                      ErrorCode::kParseError,
                      "objects[0].mesh: expected a file path string, got number"));
  EXPECT_TRUE(IsError(Parse(SceneJson(R"({"id": 1, "mesh": "", "motion": "rigid"})")),
                      ErrorCode::kInvalidArgument, "objects[0].mesh: empty path"));
  EXPECT_TRUE(IsError(Parse(SceneJson(R"({"id": 1, "mesh": "/etc/tri.obj", "motion": "rigid"})")),
                      ErrorCode::kInvalidArgument,
                      "objects[0].mesh: '/etc/tri.obj' must be relative"));
}

TEST_F(SceneIoTest, RejectsUnknownMotion) {
  EXPECT_TRUE(
      IsError(Parse(SceneJson(R"({"id": 1, "mesh": "tri.obj", "motion": "flying"})")),
              ErrorCode::kInvalidArgument,
              "objects[0].motion: unknown motion 'flying' (expected static, rigid or deformable)"));
  EXPECT_TRUE(IsError(Parse(SceneJson(R"({"id": 1, "mesh": "tri.obj", "motion": 2})")),
                      ErrorCode::kParseError, "objects[0].motion: expected a string, got number"));
}

TEST_F(SceneIoTest, RejectsMalformedPoses) {
  const std::string prefix = R"({"id": 1, "mesh": "tri.obj", "motion": "rigid", "pose": )";
  EXPECT_TRUE(IsError(Parse(SceneJson(prefix + "[1, 2, 3]}")), ErrorCode::kParseError,
                      "objects[0].pose: expected a JSON object, got array"));
  EXPECT_TRUE(IsError(Parse(SceneJson(prefix + R"({"translation": [1, 2]}})")),
                      ErrorCode::kParseError,
                      "objects[0].pose.translation: expected an array of 3 numbers, got 2 values"));
  EXPECT_TRUE(IsError(Parse(SceneJson(prefix + R"({"translation": 1}})")), ErrorCode::kParseError,
                      "objects[0].pose.translation: expected an array of 3 numbers, got number"));
  EXPECT_TRUE(IsError(Parse(SceneJson(prefix + R"({"translation": [1, "2", 3]}})")),
                      ErrorCode::kParseError,
                      "objects[0].pose.translation[1]: expected a number, got string"));
  EXPECT_TRUE(IsError(Parse(SceneJson(prefix + R"({"translation": [1, null, 3]}})")),
                      ErrorCode::kParseError,
                      "objects[0].pose.translation[1]: expected a number, got null"));
  EXPECT_TRUE(
      IsError(Parse(SceneJson(prefix + R"({"rotation_wxyz": [1, 0, 0]}})")), ErrorCode::kParseError,
              "objects[0].pose.rotation_wxyz: expected an array of 4 numbers, got 3 values"));
}

TEST_F(SceneIoTest, RejectsNonUnitQuaternions) {
  const std::string json = SceneJson(std::string(kRigid) + "," + kStatic + "," +
                                     R"({"id": 8, "mesh": "tri.obj", "motion": "rigid",)"
                                     R"( "pose": {"rotation_wxyz": [1.7, 0, 0, 0]}})");
  EXPECT_TRUE(IsError(Parse(json), ErrorCode::kInvalidArgument,
                      "objects[2].pose.rotation_wxyz: not a unit quaternion (norm 1.7)"));
  EXPECT_TRUE(IsError(Parse(SceneJson(R"({"id": 1, "mesh": "tri.obj", "motion": "rigid",)"
                                      R"( "pose": {"rotation_wxyz": [0, 0, 0, 0]}})")),
                      ErrorCode::kInvalidArgument, "not a unit quaternion (norm 0)"));
  EXPECT_TRUE(IsError(Parse(SceneJson(R"({"id": 1, "mesh": "tri.obj", "motion": "rigid",)"
                                      R"( "pose": {"rotation_wxyz": [1.0011, 0, 0, 0]}})")),
                      ErrorCode::kInvalidArgument,
                      "not a unit quaternion (norm 1.0011): |norm - 1| must be at most 0.001"));
}

// Quaternions as people write them, with four decimals, are within kQuaternionTolerance and
// are used as the unit quaternion they stand for; in frames too.
TEST_F(SceneIoTest, AcceptsAndNormalizesQuaternionsWrittenWithFourDecimals) {
  const Result<Scene> scene =
      Parse(SceneJson(R"({"id": 1, "mesh": "tri.obj", "motion": "rigid",)"
                      R"( "pose": {"rotation_wxyz": [0.7071, 0, 0, 0.7071]}})",
                      R"({"poses": [{"id": 1, "rotation_wxyz": [0.9239, 0, 0.3827, 0]}]})"));
  ASSERT_TRUE(scene.ok()) << ToString(scene.error());
  const Eigen::Quaterniond& q = scene->objects[0].X_WO.rotation;
  EXPECT_NEAR(q.norm(), 1.0, 1e-15);
  EXPECT_NEAR(q.w(), std::sqrt(0.5), 1e-15);
  EXPECT_NEAR(q.z(), std::sqrt(0.5), 1e-15);
  EXPECT_NEAR(scene->frames[0].poses[0].second.rotation.norm(), 1.0, 1e-15);
  // 0.999 and 1.001 are the edges; beyond them, refused.
  for (const char* w : {"0.9991", "1.0009"}) {
    EXPECT_TRUE(Parse(SceneJson(std::string(R"({"id": 1, "mesh": "tri.obj", "motion": "rigid",)"
                                            R"( "pose": {"rotation_wxyz": [)") +
                                w + ", 0, 0, 0]}}"))
                    .ok())
        << w;
  }
  EXPECT_TRUE(IsError(Parse(SceneJson(R"({"id": 1, "mesh": "tri.obj", "motion": "rigid",)"
                                      R"( "pose": {"rotation_wxyz": [0.998, 0, 0, 0]}})")),
                      ErrorCode::kInvalidArgument, "objects[0].pose.rotation_wxyz: not a unit"));
}

TEST_F(SceneIoTest, RejectsDuplicateIds) {
  EXPECT_TRUE(IsError(Parse(SceneJson(std::string(kRigid) + "," + kStatic + "," +
                                      R"({"id": 1, "mesh": "quad.obj", "motion": "static"})")),
                      ErrorCode::kInvalidArgument,
                      "objects[2].id: object 1 is already in the scene"));
}

TEST_F(SceneIoTest, WrapsMeshFileErrorsNamingTheObject) {
  EXPECT_TRUE(IsError(Parse(SceneJson(R"({"id": 12, "mesh": "missing.obj", "motion": "rigid"})")),
                      ErrorCode::kIoError, "objects[0].mesh: object 12: "));
  EXPECT_TRUE(IsError(Parse(SceneJson(R"({"id": 12, "mesh": "missing.obj", "motion": "rigid"})")),
                      ErrorCode::kIoError, "missing.obj: cannot open for reading"));
  WriteFile(dir_ / "broken.obj", "v 0 0 0\nv 1 0 0\nf 1 2 3\n");
  EXPECT_TRUE(IsError(Parse(SceneJson(R"({"id": 13, "mesh": "broken.obj", "motion": "static"})")),
                      ErrorCode::kParseError,
                      "objects[0].mesh: object 13: " + (dir_ / "broken.obj").string() +
                          ":3: face index 3 out of range (2 vertices)"));
  EXPECT_TRUE(IsError(Parse(SceneJson(R"({"id": 14, "mesh": "tri.off", "motion": "static"})")),
                      ErrorCode::kInvalidArgument, "objects[0].mesh: object 14: "));
}

TEST_F(SceneIoTest, RejectsMistypedFrames) {
  EXPECT_TRUE(IsError(Parse(R"({"format": "far-scene/1", "objects": [], "frames": {}})"),
                      ErrorCode::kParseError, "frames: expected an array, got object"));
  EXPECT_TRUE(IsError(Parse(SceneJson(kRigid, "[]")), ErrorCode::kParseError,
                      "frames[0]: expected a JSON object, got array"));
  EXPECT_TRUE(IsError(Parse(SceneJson(kRigid, R"({"poses": {}})")), ErrorCode::kParseError,
                      "frames[0].poses: expected an array, got object"));
  EXPECT_TRUE(IsError(Parse(SceneJson(kRigid, R"({"poses": [{"translation": [0, 0, 0]}]})")),
                      ErrorCode::kParseError, "frames[0].poses[0].id: missing"));
  EXPECT_TRUE(IsError(Parse(SceneJson(kRigid, R"({"poses": [3]})")), ErrorCode::kParseError,
                      "frames[0].poses[0]: expected a JSON object, got number"));
  EXPECT_TRUE(IsError(Parse(SceneJson(kDeformable, R"({"vertices": [{"id": 3}]})")),
                      ErrorCode::kParseError, "frames[0].vertices[0].mesh: missing"));
  EXPECT_TRUE(IsError(Parse(SceneJson(kRigid, R"({"remove": ["1"]})")), ErrorCode::kParseError,
                      "frames[0].remove[0]: expected an unsigned 32-bit integer, got string"));
  EXPECT_TRUE(IsError(Parse(SceneJson(kRigid, R"({"add": [{"id": 2}]})")), ErrorCode::kParseError,
                      "frames[0].add[0].motion: missing"));
  EXPECT_TRUE(
      IsError(Parse(SceneJson(kRigid, R"({"poses": [{"id": 1, "rotation_wxyz": [2, 0, 0, 0]}]})")),
              ErrorCode::kInvalidArgument,
              "frames[0].poses[0].rotation_wxyz: not a unit quaternion (norm 2)"));
}

TEST_F(SceneIoTest, RejectsFramesNamingUnknownIds) {
  EXPECT_TRUE(IsError(Parse(SceneJson(kRigid, R"({}, {"poses": [{"id": 5}]})")),
                      ErrorCode::kNotFound, "frames[1].poses[0].id: object 5 is not in the scene"));
  EXPECT_TRUE(
      IsError(Parse(SceneJson(kDeformable, R"({"vertices": [{"id": 4, "mesh": "tri_t1.obj"}]})")),
              ErrorCode::kNotFound, "frames[0].vertices[0].id: object 4 is not in the scene"));
  EXPECT_TRUE(IsError(Parse(SceneJson(kRigid, R"({"remove": [1, 1]})")), ErrorCode::kNotFound,
                      "frames[0].remove[1]: object 1 is not in the scene"));
}

TEST_F(SceneIoTest, AppliesFramesInOrderForIdBookkeeping) {
  // Removed in frame 0: a pose in frame 1 names an unknown id.
  EXPECT_TRUE(IsError(Parse(SceneJson(kRigid, R"({"remove": [1]}, {"poses": [{"id": 1}]})")),
                      ErrorCode::kNotFound, "frames[1].poses[0].id: object 1 is not in the scene"));
  // Removal comes before poses within a frame.
  EXPECT_TRUE(IsError(Parse(SceneJson(kRigid, R"({"poses": [{"id": 1}], "remove": [1]})")),
                      ErrorCode::kNotFound, "frames[0].poses[0].id: object 1 is not in the scene"));
  // Added in frame 0, posed in frame 1; removed and added again in one frame.
  const Result<Scene> scene = Parse(SceneJson(
      kRigid, R"({"add": [{"id": 9, "mesh": "tri.obj", "motion": "rigid"}], "poses": [{"id": 9}]},)"
              R"({"remove": [9], "add": [{"id": 9, "mesh": "quad.obj", "motion": "deformable"}]},)"
              R"({"vertices": [{"id": 9, "mesh": "quad.obj"}]})"));
  EXPECT_TRUE(scene.ok()) << ToString(scene.error());
}

TEST_F(SceneIoTest, RejectsPoseForStaticObject) {
  EXPECT_TRUE(
      IsError(Parse(SceneJson(kStatic, R"({"poses": [{"id": 2, "translation": [1, 0, 0]}]})")),
              ErrorCode::kInvalidArgument,
              "frames[0].poses[0].id: object 2 is static; static objects take no poses"));
}

TEST_F(SceneIoTest, RejectsTwoPosesForOneObjectInOneFrame) {
  EXPECT_TRUE(IsError(Parse(SceneJson(kRigid, R"({"poses": [{"id": 1}, {"id": 1}]})")),
                      ErrorCode::kInvalidArgument,
                      "frames[0].poses[1].id: second pose for object 1"));
  EXPECT_TRUE(IsError(Parse(SceneJson(kDeformable, R"({"vertices": [{"id": 3, "mesh": "tri.obj"},)"
                                                   R"( {"id": 3, "mesh": "tri_t1.obj"}]})")),
                      ErrorCode::kInvalidArgument,
                      "frames[0].vertices[1].id: second vertex update for object 3"));
}

TEST_F(SceneIoTest, RejectsVerticesForNonDeformableObject) {
  EXPECT_TRUE(IsError(
      Parse(SceneJson(kRigid, R"({"vertices": [{"id": 1, "mesh": "tri_t1.obj"}]})")),
      ErrorCode::kInvalidArgument,
      "frames[0].vertices[0].id: object 1 is rigid; only deformable objects take vertices"));
  EXPECT_TRUE(IsError(Parse(SceneJson(kStatic, R"({"vertices": [{"id": 2, "mesh": "quad.obj"}]})")),
                      ErrorCode::kInvalidArgument, "object 2 is static; only deformable"));
}

TEST_F(SceneIoTest, RejectsVertexFilesThatDoNotMatchTheMesh) {
  EXPECT_TRUE(IsError(
      Parse(SceneJson(kDeformable, R"({"vertices": [{"id": 3, "mesh": "quad.obj"}]})")),
      ErrorCode::kInvalidArgument, "frames[0].vertices[0].mesh: 4 vertices given, object 3 has 3"));
  WriteFile(dir_ / "flipped.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 3 2\n");
  EXPECT_TRUE(
      IsError(Parse(SceneJson(kDeformable, R"({"vertices": [{"id": 3, "mesh": "flipped.obj"}]})")),
              ErrorCode::kInvalidArgument,
              "frames[0].vertices[0].mesh: vertex file's triangle 0 differs from object 3's"));
  WriteFile(dir_ / "two.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 3 2 1\n");
  EXPECT_TRUE(
      IsError(Parse(SceneJson(kDeformable, R"({"vertices": [{"id": 3, "mesh": "two.obj"}]})")),
              ErrorCode::kInvalidArgument, "vertex file has 2 triangles, object 3 has 1"));
  EXPECT_TRUE(
      IsError(Parse(SceneJson(kDeformable, R"({"vertices": [{"id": 3, "mesh": "gone.obj"}]})")),
              ErrorCode::kIoError, "frames[0].vertices[0].mesh: object 3: "));
}

TEST_F(SceneIoTest, RejectsAddOfExistingId) {
  EXPECT_TRUE(IsError(
      Parse(SceneJson(kRigid, R"({"add": [{"id": 1, "mesh": "quad.obj", "motion": "static"}]})")),
      ErrorCode::kInvalidArgument, "frames[0].add[0].id: object 1 is already in the scene"));
}

TEST_F(SceneIoTest, ReadScenePrefixesErrorsWithTheScenePath) {
  WriteFile(dir_ / "s.json", SceneJson(R"({"id": 1, "mesh": "tri.obj", "motion": "walking"})"));
  EXPECT_TRUE(IsError(ReadScene(dir_ / "s.json"), ErrorCode::kInvalidArgument,
                      (dir_ / "s.json").string() + ": objects[0].motion: unknown motion"));
}

// Writer errors: nothing is written for an invalid scene.

TEST_F(SceneIoTest, WriteSceneRejectsInvalidScenesBeforeWriting) {
  const Result<Mesh> triangle = ReadObj(kTriangleObj, "tri");
  ASSERT_TRUE(triangle.ok());
  TempDir out;
  Scene duplicate;
  duplicate.objects.push_back({1, "a.obj", *triangle, Motion::kStatic, Pose{}});
  duplicate.objects.push_back({1, "b.obj", *triangle, Motion::kStatic, Pose{}});
  EXPECT_TRUE(IsError(WriteScene(duplicate, out / "s.json"), ErrorCode::kInvalidArgument,
                      "objects[1].id: object 1 is already in the scene"));
  EXPECT_FALSE(std::filesystem::exists(out / "a.obj"));
  EXPECT_FALSE(std::filesystem::exists(out / "s.json"));

  Scene bad_rotation;
  bad_rotation.objects.push_back({1, "a.obj", *triangle, Motion::kRigid, Pose{}});
  bad_rotation.objects[0].X_WO.rotation = Eigen::Quaterniond(2, 0, 0, 0);
  EXPECT_TRUE(IsError(WriteScene(bad_rotation, out / "s.json"), ErrorCode::kInvalidArgument,
                      "objects[0].pose.rotation_wxyz: not a unit quaternion (norm 2)"));

  Scene static_pose;
  static_pose.objects.push_back({1, "a.obj", *triangle, Motion::kStatic, Pose{}});
  static_pose.frames.emplace_back().poses.emplace_back(1, Pose{});
  EXPECT_TRUE(IsError(WriteScene(static_pose, out / "s.json"), ErrorCode::kInvalidArgument,
                      "frames[0].poses[0].id: object 1 is static"));

  Scene empty_mesh;
  empty_mesh.objects.push_back({1, "a.obj", Mesh{}, Motion::kStatic, Pose{}});
  EXPECT_TRUE(IsError(WriteScene(empty_mesh, out / "s.json"), ErrorCode::kInvalidArgument,
                      "objects[0].mesh: no triangles"));
  EXPECT_FALSE(std::filesystem::exists(out / "s.json"));
}

TEST_F(SceneIoTest, WriteSceneRejectsBadMeshPaths) {
  const Result<Mesh> triangle = ReadObj(kTriangleObj, "tri");
  const Result<Mesh> quad = ReadObj(kQuadObj, "quad");
  ASSERT_TRUE(triangle.ok() && quad.ok());
  TempDir out;
  Scene scene;
  scene.objects.push_back({1, "", *triangle, Motion::kStatic, Pose{}});
  EXPECT_TRUE(IsError(WriteScene(scene, out / "s.json"), ErrorCode::kInvalidArgument,
                      "objects[0].mesh: empty mesh path"));
  scene.objects[0].mesh_path = "/tmp/abs.obj";
  EXPECT_TRUE(IsError(WriteScene(scene, out / "s.json"), ErrorCode::kInvalidArgument,
                      "objects[0].mesh: '/tmp/abs.obj' must be relative"));
  scene.objects[0].mesh_path = "m.obj";
  scene.objects.push_back({2, "m.obj", *quad, Motion::kStatic, Pose{}});
  EXPECT_TRUE(
      IsError(WriteScene(scene, out / "s.json"), ErrorCode::kInvalidArgument,
              "objects[1].mesh: 'm.obj' is also used by objects[0].mesh with a different mesh"));
  scene.objects[1].mesh_path = "m.off";
  EXPECT_TRUE(
      IsError(WriteScene(scene, out / "s.json"), ErrorCode::kInvalidArgument,
              "objects[1].mesh: " + (out / "m.off").string() + ": unknown mesh file extension"));
}

TEST_F(SceneIoTest, WriteSceneReportsUnwritableSceneFile) {
  const Result<Scene> scene = Parse(SceneJson(kRigid));
  ASSERT_TRUE(scene.ok());
  WriteFile(dir_ / "file", "x");
  // A path under a regular file cannot be created.
  EXPECT_TRUE(IsError(WriteScene(*scene, dir_ / "file" / "s.json"), ErrorCode::kIoError,
                      "cannot open for writing"));
}

}  // namespace
}  // namespace far
