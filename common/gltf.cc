#include "common/gltf.h"

#include <algorithm>
#include <cstring>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#define TINYGLTF_IMPLEMENTATION
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <tiny_gltf.h>

#include "common/atomic_file.h"
#include "common/errors.h"

namespace docunfold {
namespace {

// Appends raw bytes to the single buffer, 4-byte aligned, and returns a view.
int AddView(tinygltf::Model* model, const void* data, size_t bytes, int target) {
  std::vector<unsigned char>& buf = model->buffers[0].data;
  while (buf.size() % 4) buf.push_back(0);
  tinygltf::BufferView view;
  view.buffer = 0;
  view.byteOffset = buf.size();
  view.byteLength = bytes;
  if (target) view.target = target;
  const auto* p = static_cast<const unsigned char*>(data);
  buf.insert(buf.end(), p, p + bytes);
  model->bufferViews.push_back(view);
  return int(model->bufferViews.size() - 1);
}

int AddAccessor(tinygltf::Model* model, int view, int component, int type, size_t count,
                std::vector<double> min = {}, std::vector<double> max = {}) {
  tinygltf::Accessor a;
  a.bufferView = view;
  a.componentType = component;
  a.type = type;
  a.count = count;
  a.minValues = std::move(min);
  a.maxValues = std::move(max);
  model->accessors.push_back(a);
  return int(model->accessors.size() - 1);
}

// Positions in glTF's axes (y up, z towards the viewer: OpenCV's y and z
// flipped), with the bounds the specification requires; the accessor index.
int AddPositions(tinygltf::Model* model, const std::vector<Eigen::Vector3d>& positions) {
  std::vector<float> pos;
  std::vector<double> lo(3, 1e300), hi(3, -1e300);
  for (const Eigen::Vector3d& p : positions) {
    const double q[3] = {p.x(), -p.y(), -p.z()};
    for (int k = 0; k < 3; ++k) {
      pos.push_back(float(q[k]));
      lo[k] = std::min(lo[k], double(float(q[k])));
      hi[k] = std::max(hi[k], double(float(q[k])));
    }
  }
  return AddAccessor(model,
                     AddView(model, pos.data(), pos.size() * 4, TINYGLTF_TARGET_ARRAY_BUFFER),
                     TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, positions.size(), lo, hi);
}

// One primitive with its material, as a named mesh in a node of `scene`.
void AddNode(tinygltf::Model* model, tinygltf::Scene* scene, const std::string& name,
             tinygltf::Primitive prim, const tinygltf::Material& material) {
  model->materials.push_back(material);
  prim.material = int(model->materials.size() - 1);
  tinygltf::Mesh mesh;
  mesh.name = name;
  mesh.primitives.push_back(prim);
  model->meshes.push_back(mesh);
  tinygltf::Node node;
  node.name = name;
  node.mesh = int(model->meshes.size() - 1);
  model->nodes.push_back(node);
  scene->nodes.push_back(int(model->nodes.size() - 1));
}

}  // namespace

void WriteGlb(const std::filesystem::path& path, const std::vector<GltfMesh>& meshes,
              const std::vector<GltfPoints>& clouds) {
  tinygltf::Model model;
  model.asset.version = "2.0";
  model.asset.generator = "docunfold";
  model.buffers.resize(1);
  tinygltf::Scene scene;
  for (const GltfMesh& m : meshes) {
    if (m.positions.empty() || m.triangles.empty())
      throw std::invalid_argument("WriteGlb: empty mesh " + m.name);
    std::vector<uint32_t> idx;
    for (const Triangle& t : m.triangles)
      // Flipping two axes keeps handedness, so the winding stays as given.
      for (int k = 0; k < 3; ++k) idx.push_back(uint32_t(t[k]));

    tinygltf::Primitive prim;
    prim.mode = TINYGLTF_MODE_TRIANGLES;
    prim.attributes["POSITION"] = AddPositions(&model, m.positions);
    prim.indices = AddAccessor(
        &model, AddView(&model, idx.data(), idx.size() * 4, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER),
        TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, TINYGLTF_TYPE_SCALAR, idx.size(), {0.0},
        {double(m.positions.size() - 1)});
    tinygltf::Material material;
    material.name = m.name;
    material.doubleSided = true;
    material.pbrMetallicRoughness.metallicFactor = 0.0;
    material.pbrMetallicRoughness.roughnessFactor = 1.0;
    if (!m.texcoords.empty() && !m.texture.empty()) {
      if (m.texcoords.size() != m.positions.size())
        throw std::invalid_argument("WriteGlb: texcoords size mismatch");
      std::vector<float> uv;
      for (const Eigen::Vector2d& t : m.texcoords) {
        uv.push_back(float(t.x()));
        uv.push_back(float(t.y()));
      }
      prim.attributes["TEXCOORD_0"] = AddAccessor(
          &model, AddView(&model, uv.data(), uv.size() * 4, TINYGLTF_TARGET_ARRAY_BUFFER),
          TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC2, m.texcoords.size());
      std::vector<unsigned char> png;
      cv::imencode(".png", m.texture, png);
      tinygltf::Image image;
      image.name = m.name + "_texture";
      image.mimeType = "image/png";
      image.bufferView = AddView(&model, png.data(), png.size(), 0);
      model.images.push_back(image);
      tinygltf::Sampler sampler;
      sampler.magFilter = TINYGLTF_TEXTURE_FILTER_LINEAR;
      sampler.minFilter = TINYGLTF_TEXTURE_FILTER_LINEAR_MIPMAP_LINEAR;
      sampler.wrapS = sampler.wrapT = TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE;
      model.samplers.push_back(sampler);
      tinygltf::Texture texture;
      texture.source = int(model.images.size() - 1);
      texture.sampler = int(model.samplers.size() - 1);
      model.textures.push_back(texture);
      material.pbrMetallicRoughness.baseColorTexture.index = int(model.textures.size() - 1);
    }
    AddNode(&model, &scene, m.name, prim, material);
  }
  for (const GltfPoints& c : clouds) {
    if (c.positions.empty()) continue;
    tinygltf::Primitive prim;
    prim.mode = TINYGLTF_MODE_POINTS;
    prim.attributes["POSITION"] = AddPositions(&model, c.positions);
    if (!c.colors.empty()) {
      if (c.colors.size() != c.positions.size())
        throw std::invalid_argument("WriteGlb: point colours size mismatch");
      std::vector<float> col;
      for (const Eigen::Vector3f& v : c.colors)
        for (int k = 0; k < 3; ++k) col.push_back(std::clamp(v[k], 0.0f, 1.0f));
      prim.attributes["COLOR_0"] = AddAccessor(
          &model, AddView(&model, col.data(), col.size() * 4, TINYGLTF_TARGET_ARRAY_BUFFER),
          TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, c.colors.size());
    }
    tinygltf::Material material;
    material.name = c.name;
    material.pbrMetallicRoughness.metallicFactor = 0.0;
    material.pbrMetallicRoughness.roughnessFactor = 1.0;
    AddNode(&model, &scene, c.name, prim, material);
  }
  model.scenes.push_back(scene);
  model.defaultScene = 0;

  AtomicOutput out(path);
  tinygltf::TinyGLTF writer;
  if (!writer.WriteGltfSceneToFile(&model, out.temp_path().string(),
                                   /*embedImages=*/true, /*embedBuffers=*/true,
                                   /*prettyPrint=*/false, /*writeBinary=*/true))
    throw OutputError(path.string() + ": cannot write glTF");
  out.Commit();
}

}  // namespace docunfold
