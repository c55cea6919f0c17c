// CSG: the built-in CSG scenes and the scene JSON's "csg" tree, the reference (raycast casts the
// tree's result), the csg algorithm's depth peeling against it, and that a plain z-buffer of the
// same scene is wrong where the tree cuts or intersects.
#include <gtest/gtest.h>

#include <hsr/render.hpp>

#include <fstream>
#include <string>

#include "algorithms/algorithms.hpp"
#include "cli_runner.hpp"
#include "conformance.hpp"

namespace hsr {
namespace {

const char* kOps[] = {"difference", "intersection", "union", "mixed"};

std::string csgScene(const char* op) { return std::string("builtin:csg?op=") + op; }

conformance::Outcome against(const char* algorithm, const std::string& name,
                             std::map<std::string, std::string> params = {}) {
  const Scene scene = loadScene(name);
  const conformance::Variant variant{findAlgorithm(algorithm), std::move(params)};
  return conformance::run(variant, name, scene, conformance::ownPose(scene), 160, 120, DepthFormat());
}

TEST(Csg, BuiltInScenesCarryATreeWithItsRootLast) {
  for (const char* op : kOps) {
    const Scene scene = loadScene(csgScene(op));
    ASSERT_FALSE(scene.csg.empty()) << op;
    EXPECT_NE(scene.csg.back().op, CsgNode::Op::Solid) << op;
    const algo::CsgTree tree(scene);
    EXPECT_EQ(tree.solids(), std::string(op) == "mixed" ? 5u : 2u) << op;
    EXPECT_TRUE(algo::csgSolidsWithinDepthRange(scene, resolveCamera(*scene.camera, 64, 48, scene.bounds()))) << op;
  }
}

TEST(Csg, TheTreeEvaluatesItsSetOperations) {
  const Scene scene = loadScene("builtin:csg?op=mixed");  // (cube & sphere) - (bar-x | bar-y | bar-z)
  const algo::CsgTree tree(scene);
  EXPECT_FALSE(tree.contains(0));
  EXPECT_FALSE(tree.contains(0b00001));  // the cube alone
  EXPECT_TRUE(tree.contains(0b00011));   // cube and sphere
  EXPECT_FALSE(tree.contains(0b00111));  // and a bar
  EXPECT_FALSE(tree.contains(0b10011));
}

// The csg algorithm shows the reference's image on each built-in CSG scene with its own camera,
// peeling at least three layers for the trees that cut or trim (a union seen from outside shows
// its first layer).
TEST(Csg, DepthPeelingMatchesTheReference) {
  for (const char* op : kOps) {
    const conformance::Outcome o = against("csg", csgScene(op));
    EXPECT_EQ(o.wrong, 0u) << op << "\n" << o.replay;
    EXPECT_GT(o.covered, 4000u) << op;
    const Scene scene = loadScene(csgScene(op));
    RenderOptions options;
    options.algorithm = "csg";
    const Frame frame = render(scene, resolveCamera(*scene.camera, 160, 120, scene.bounds()), options);
    EXPECT_EQ(frame.stats.detailCount("undecided_pixels"), 0u) << op;
    EXPECT_GE(frame.stats.detailCount("layers").value_or(0), std::string(op) == "union" ? 1u : 3u) << op;
  }
}

// The conformance suite judges csg on its CSG cases wherever every solid lies between the planes:
// most of the seeded poses (the others cut a solid with the near or far plane), each checked
// there with zero wrong pixels.
TEST(Csg, TheSuiteJudgesMostOfItsCsgPoses) {
  const conformance::Plan plan = conformance::fullPlan();
  int cases = 0;
  for (const conformance::Plan::Case& c : plan.cases) {
    const Scene scene = conformance::load(c.scene);
    if (scene.csg.empty()) continue;
    ++cases;
    int judged = 0;
    for (const conformance::Pose& pose : conformance::posesAround(scene, c.poses, std::hash<std::string>{}(c.scene) & 0xffff)) {
      const Camera camera = resolveCamera(pose.spec, 64, 48, scene.bounds());
      if (!algo::csgSolidsWithinDepthRange(scene, camera)) continue;
      ++judged;
      const conformance::Outcome o = conformance::run({findAlgorithm("csg"), {}}, c.scene, scene, pose, 64, 48, DepthFormat());
      EXPECT_EQ(o.wrong, 0u) << o.replay;
    }
    EXPECT_GE(judged * 2, c.poses) << c.scene << ": " << judged << " of " << c.poses << " poses judged";
  }
  EXPECT_EQ(cases, 4);
}

// A plain z-buffer draws the solids as meshes: wrong where the tree cuts (difference) or trims
// (intersection), right for a union seen from outside (its visible surface is the nearest).
TEST(Csg, APlainZbufferOfACsgSceneIsWrongWhereTheTreeCutsOrTrims) {
  for (const char* op : {"difference", "intersection", "mixed"}) {
    const conformance::Outcome o = against("zbuffer", csgScene(op));
    EXPECT_GT(o.wrong, 500u) << op;
  }
  EXPECT_EQ(against("zbuffer", csgScene("union")).wrong, 0u);
}

// Too few layers: the pixels that need more show the background, counted, and wrong.
TEST(Csg, TooFewLayersLeavePixelsUndecided) {
  const Scene scene = loadScene("builtin:csg");
  RenderOptions options;
  options.algorithm = "csg";
  options.params = {{"max-layers", "1"}};
  const Frame frame = render(scene, resolveCamera(*scene.camera, 160, 120, scene.bounds()), options);
  EXPECT_EQ(frame.stats.detailCount("layers"), 1u);
  EXPECT_GT(frame.stats.detailCount("undecided_pixels").value_or(0), 500u);
  EXPECT_GT(against("csg", "builtin:csg", {{"max-layers", "1"}}).wrong, 500u);
}

// Without a tree, the first layer decides every pixel: the z-buffer's image.
TEST(Csg, WithoutATreeItIsTheZbuffer) {
  const Scene scene = loadScene("builtin:cubes");
  const Camera camera = resolveCamera(*scene.camera, 97, 61, scene.bounds());
  RenderOptions options;
  options.algorithm = "csg";
  const Frame csg = render(scene, camera, options);
  options.algorithm = "zbuffer";
  options.params = {{"raster", "binned"}};
  const Frame zbuffer = render(scene, camera, options);
  EXPECT_EQ(csg.faceId, zbuffer.faceId);
  EXPECT_EQ(csg.depth, zbuffer.depth);
  EXPECT_EQ(csg.stats.detailCount("layers"), 1u);
}

// The reference knows a ray that starts inside a solid: from inside the cube (near plane in it),
// the difference's first surface is where the ray leaves the material, not the first hit.
TEST(Csg, TheReferenceCountsTheSolidsHoldingTheRaysStart) {
  const Scene scene = loadScene("builtin:csg");  // cube - sphere at (0.75, 0.75, 0.75), radius 1
  CameraSpec spec;
  spec.eye = {-0.5, -0.5, -0.5};  // inside the cube, outside the sphere: inside the result
  spec.target = {-0.5, -0.5, -2};  // looking at the cube's -z face from within
  spec.up = {0, 1, 0};
  spec.near = 0.1;
  spec.far = 10;
  const Camera camera = resolveCamera(spec, 9, 9, scene.bounds());
  EXPECT_FALSE(algo::csgSolidsWithinDepthRange(scene, camera));
  RenderOptions options;
  options.algorithm = "raycast";
  const Frame frame = render(scene, camera, options);
  const size_t centre = frame.index(4, 4);
  ASSERT_GE(frame.faceId[centre], 0);
  EXPECT_EQ(frame.faceId[centre], 4);  // the cube's -z face (its fifth), left from inside
  EXPECT_NEAR(frame.depth[centre], 0.5, 1e-6);
}

class CsgJson : public test::CliTest {
 protected:
  std::string write(const std::string& name, const std::string& csg) {
    writeFile(name, R"({"meshes": [{"builtin": "cubes", "name": "a"},
  {"builtin": "sphere?n=80", "name": "b", "scale": 1.5},
  {"builtin": "sphere?n=80", "translate": [1, 0, 0]}],
 "csg": )" + csg + "}\n");
    return path(name);
  }
};

TEST_F(CsgJson, LeavesNameEntriesByIndexOrName) {
  const Scene scene = loadScene(write("t.json", R"({"difference": ["a", {"union": [1, 2]}]})"));
  ASSERT_EQ(scene.csg.size(), 5u);  // a, b, 2, b | 2, a - (b | 2)
  EXPECT_EQ(scene.csg[0].op, CsgNode::Op::Solid);
  EXPECT_EQ(scene.csg[0].first, 0u);
  EXPECT_EQ(scene.csg[0].count, 24u);  // the four cubes
  EXPECT_EQ(scene.csg[3].op, CsgNode::Op::Union);
  EXPECT_EQ(scene.csg[4].op, CsgNode::Op::Difference);
  EXPECT_EQ(scene.csg[4].left, 0u);
  EXPECT_EQ(scene.csg[4].right, 3u);
  // Three operands of a difference: the first less the union of the others.
  const Scene three = loadScene(write("u.json", R"({"difference": [0, 1, 2]})"));
  ASSERT_EQ(three.csg.size(), 5u);
  EXPECT_EQ(three.csg[3].op, CsgNode::Op::Union);
  EXPECT_EQ(three.csg[4].op, CsgNode::Op::Difference);
}

TEST_F(CsgJson, ABadTreeIsOneLineNamingTheFileAndLine) {
  const std::pair<const char*, const char*> cases[] = {
      {R"({"xor": [0, 1]})", "unknown operation 'xor'"},
      {R"({"union": [0]})", "two or more nodes"},
      {R"({"union": [0, 7]})", "mesh index 7 is not one of meshes[0..2]"},
      {R"({"union": [0, -1]})", "mesh index -1"},
      {R"({"union": ["a", "c"]})", "no mesh entry is named 'c'"},
      {R"({"union": [0, "a"]})", "meshes[0] is named twice"},
      {R"({"union": [0, 1.5]})", "a node must be"},
      {R"({"union": [0, 1], "intersection": [1, 2]})", "a node must be"},
      {R"([0, 1])", "a node must be"},
  };
  for (const auto& [tree, problem] : cases) {
    const std::string file = write("bad.json", tree);
    const test::CliResult r = hsr("render bad.json -o out.png");
    EXPECT_EQ(r.status, 2) << tree << "\n" << r;
    EXPECT_TRUE(r.oneErrorLine()) << r;
    EXPECT_NE(r.err.find("bad.json:4: csg: "), std::string::npos) << r;
    EXPECT_NE(r.err.find(problem), std::string::npos) << tree << "\n" << r;
  }
}

TEST_F(CsgJson, CullingACsgSceneIsBadInput) {
  for (const char* algorithm : {"csg", "raycast"}) {
    const test::CliResult r = hsr(std::string("render builtin:csg --algorithm ") + algorithm + " --cull back -o out.png");
    EXPECT_EQ(r.status, 2) << r;
    EXPECT_TRUE(r.oneErrorLine()) << r;
    EXPECT_NE(r.err.find("culling off"), std::string::npos) << r;
  }
}

TEST_F(CsgJson, VerifyJudgesTheCsgAlgorithmAgainstTheTreesResult) {
  const test::CliResult ok = hsr("render 'builtin:csg?op=mixed' --algorithm csg --verify --json -o out.png");
  ASSERT_EQ(ok.status, 0) << ok;
  EXPECT_NE(ok.out.find("\"wrong_pixels\": 0"), std::string::npos) << ok;
  const test::CliResult plain = hsr("render 'builtin:csg?op=mixed' --algorithm zbuffer --verify --json -o out.png");
  EXPECT_EQ(plain.out.find("\"wrong_pixels\": 0"), std::string::npos) << plain;
}

}  // namespace
}  // namespace hsr
