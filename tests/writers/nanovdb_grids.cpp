// Writes the NanoVDB grids the tests read, with the NanoVDB library
// itself (Debian's libnanovdb-dev): a fog-volume sphere as Float, Fp16,
// Fp8 and Fp4 values (and as Float at a fifth of the voxel size), and a
// level-set torus. Each grid goes to NAME.blob
// (its buffer as it lies in memory), NAME.f32 (the library's own value of
// every voxel of its index box, x fastest) and grids.nvdb (all of them,
// NanoVDB's file format); stdout gets a JSON object describing each.
// With `bench` or `seed` after the folder: the benchmarks' larger grid,
// or the fuzz target's seed, alone.
#include <nanovdb/util/IO.h>
#include <nanovdb/util/Primitives.h>

#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

static const nanovdb::Vec3f kCenter(1.5f, -2.0f, 0.5f);
static const nanovdb::Vec3d kOrigin(0.25, -0.5, 1.0);
static const double kVoxel = 0.5;

template <typename BuildT>
static void describe(const nanovdb::GridHandle<nanovdb::HostBuffer> &handle, const char *name,
                     const char *type, const std::string &dir, bool last) {
  const nanovdb::NanoGrid<BuildT> *grid = handle.grid<BuildT>();
  std::ofstream(dir + "/" + name + ".blob", std::ios::binary)
      .write(reinterpret_cast<const char *>(handle.data()), handle.size());
  const nanovdb::CoordBBox box = grid->indexBBox();
  const nanovdb::Coord lo = box.min(), hi = box.max();
  std::vector<float> dense;
  auto acc = grid->getAccessor();
  for (int k = lo[2]; k <= hi[2]; ++k)
    for (int j = lo[1]; j <= hi[1]; ++j)
      for (int i = lo[0]; i <= hi[0]; ++i)
        dense.push_back(float(acc.getValue(nanovdb::Coord(i, j, k))));
  std::ofstream(dir + "/" + name + ".f32", std::ios::binary)
      .write(reinterpret_cast<const char *>(dense.data()), dense.size() * sizeof(float));
  const nanovdb::Vec3d w = grid->indexToWorld(nanovdb::Vec3d(lo[0], lo[1], lo[2]));
  std::printf("\"%s\": {\"type\": \"%s\", \"lo\": [%d, %d, %d], \"hi\": [%d, %d, %d], "
              "\"world_lo\": [%.9g, %.9g, %.9g], \"voxel\": %.9g, \"active\": %llu, "
              "\"bytes\": %llu, \"background\": %.9g}%s\n",
              name, type, lo[0], lo[1], lo[2], hi[0], hi[1], hi[2], w[0], w[1], w[2],
              grid->voxelSize()[0], (unsigned long long)grid->activeVoxelCount(),
              (unsigned long long)handle.size(), double(grid->tree().background()),
              last ? "" : ",");
}

int main(int argc, char **argv) {
  const std::string dir = argc > 1 ? argv[1] : ".";
  // `DIR bench`: the benchmarks' grid alone, a fog sphere 240 voxels
  // across in index space (voxel size 1, origin 0), as DIR/bench.blob.
  // `DIR seed`: the fuzz target's seed, the smallest grid with every
  // kind of node (one root tile, upper and lower node, a few leaves).
  if (argc > 2 && std::string(argv[2]) == "seed") {
    auto seed = nanovdb::createFogVolumeSphere<float, float>(
        2.0f, nanovdb::Vec3f(4.0f), 1.0, 1.0, nanovdb::Vec3d(0.0), "seed");
    std::printf("{\n");
    describe<float>(seed, "seed", "Float", dir, true);
    std::printf("}\n");
    return 0;
  }
  if (argc > 2 && std::string(argv[2]) == "bench") {
    auto bench = nanovdb::createFogVolumeSphere<float, float>(
        120.0f, nanovdb::Vec3f(0.0f), 1.0, 3.0, nanovdb::Vec3d(0.0), "bench");
    std::printf("{\n");
    describe<float>(bench, "bench", "Float", dir, true);
    std::printf("}\n");
    return 0;
  }
  using nanovdb::Fp16;
  using nanovdb::Fp4;
  using nanovdb::Fp8;
  std::vector<nanovdb::GridHandle<nanovdb::HostBuffer>> handles;
  handles.push_back(nanovdb::createFogVolumeSphere<float, float>(6.0f, kCenter, kVoxel, 3.0,
                                                                 kOrigin, "fog"));
  handles.push_back(
      nanovdb::createFogVolumeSphere<float, Fp16>(6.0f, kCenter, kVoxel, 3.0, kOrigin, "fog16"));
  handles.push_back(
      nanovdb::createFogVolumeSphere<float, Fp8>(6.0f, kCenter, kVoxel, 3.0, kOrigin, "fog8"));
  handles.push_back(
      nanovdb::createFogVolumeSphere<float, Fp4>(6.0f, kCenter, kVoxel, 3.0, kOrigin, "fog4"));
  handles.push_back(nanovdb::createLevelSetTorus<float, float>(5.0f, 2.0f, kCenter, kVoxel, 3.0,
                                                               kOrigin, "torus"));
  handles.push_back(nanovdb::createFogVolumeSphere<float, float>(6.0f, kCenter, kVoxel / 5, 3.0,
                                                                 kOrigin, "fog_fine"));
  std::printf("{\n");
  describe<float>(handles[0], "fog", "Float", dir, false);
  describe<Fp16>(handles[1], "fog16", "Fp16", dir, false);
  describe<Fp8>(handles[2], "fog8", "Fp8", dir, false);
  describe<Fp4>(handles[3], "fog4", "Fp4", dir, false);
  describe<float>(handles[4], "torus", "Float", dir, false);
  describe<float>(handles[5], "fog_fine", "Float", dir, true);
  std::printf("}\n");
  nanovdb::io::writeGrids(dir + "/grids.nvdb", handles);
  return 0;
}
