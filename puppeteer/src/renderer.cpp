// SPDX-License-Identifier: MIT
// OpenGL 3.3 core rendering of the live app: shaders (as raw strings), buffer uploads, draw calls, read-back.
#include "renderer.h"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include <algorithm>
#include <cstddef>
#include <cstring>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>

#include "textures.h"

namespace imps::app {
namespace {

// sRGB encoding shared by every fragment shader: the framebuffer holds sRGB bytes, the maths is in linear light.
#define IMPS_GLSL_SRGB                                                                      \
  "vec3 srgb(vec3 c) {\n"                                                                   \
  "  c = clamp(c, 0.0, 1.0);\n"                                                             \
  "  return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(0.0031308, c));\n" \
  "}\n"

const char* const kMeshVertex = R"(#version 330 core
layout(location = 0) in vec3 aPosition;
layout(location = 1) in vec3 aNormal;
layout(location = 2) in vec3 aColor;
uniform mat4 uView;
uniform mat4 uProjection;
out vec3 vNormal;
out vec3 vColor;
out vec3 vViewPosition;
void main() {
  vec4 p = uView * vec4(aPosition, 1.0);
  vViewPosition = p.xyz;
  vNormal = mat3(uView) * aNormal;
  vColor = aColor;
  gl_Position = uProjection * p;
}
)";

const char* const kMeshFragment = "#version 330 core\n" IMPS_GLSL_SRGB R"(
in vec3 vNormal;
in vec3 vColor;
in vec3 vViewPosition;
uniform vec3 uLight;      // towards the light, camera space, unit
uniform float uAmbient;
uniform float uRim;
uniform int uHasNormals;
out vec4 fragColor;
void main() {
  vec3 faceNormal = normalize(cross(dFdx(vViewPosition), dFdy(vViewPosition)));
  vec3 n = uHasNormals != 0 ? vNormal : faceNormal;
  float len = length(n);
  n = len > 0.0 ? n / len : faceNormal;
  vec3 toEye = -vViewPosition;
  if (dot(n, toEye) < 0.0) n = -n;  // two-sided: back faces lit as if they faced the camera
  float diffuse = max(dot(n, uLight), 0.0);
  float rim = pow(1.0 - clamp(n.z, 0.0, 1.0), 3.0);
  vec3 c = vColor * (uAmbient + (1.0 - uAmbient) * diffuse) + vec3(uRim * rim);
  fragColor = vec4(srgb(c), 1.0);
}
)";

// Textured meshes (mesh.h's layers) are drawn from unshared corners: each triangle's up to three heaviest layers,
// their image slots (flat: the same at the three corners), (u, v) and weights.
const char* const kTexturedVertex = R"(#version 330 core
layout(location = 0) in vec3 aPosition;
layout(location = 1) in vec3 aNormal;
layout(location = 2) in vec3 aColor;
layout(location = 3) in ivec3 aSlots;
layout(location = 4) in vec4 aUv01;
layout(location = 5) in vec2 aUv2;
layout(location = 6) in vec3 aWeights;
uniform mat4 uView;
uniform mat4 uProjection;
out vec3 vNormal;
out vec3 vColor;
out vec3 vViewPosition;
flat out ivec3 vSlots;
out vec4 vUv01;
out vec2 vUv2;
out vec3 vWeights;
void main() {
  vec4 p = uView * vec4(aPosition, 1.0);
  vViewPosition = p.xyz;
  vNormal = mat3(uView) * aNormal;
  vColor = aColor;
  vSlots = aSlots;
  vUv01 = aUv01;
  vUv2 = aUv2;
  vWeights = aWeights;
  gl_Position = uProjection * p;
}
)";

const char* const kTexturedFragment = "#version 330 core\n" IMPS_GLSL_SRGB R"(
in vec3 vNormal;
in vec3 vColor;
in vec3 vViewPosition;
flat in ivec3 vSlots;
in vec4 vUv01;
in vec2 vUv2;
in vec3 vWeights;
uniform sampler2DArray uTextures;  // sRGB images, rows from the top: v = 1 is the first row
uniform vec3 uLight;
uniform float uAmbient;
uniform float uRim;
uniform int uHasNormals;
out vec4 fragColor;
vec3 texel(int slot, vec2 uv) {
  return slot < 0 ? vec3(1.0) : texture(uTextures, vec3(uv.x, 1.0 - uv.y, float(slot))).rgb;
}
void main() {
  vec3 faceNormal = normalize(cross(dFdx(vViewPosition), dFdy(vViewPosition)));
  vec3 n = uHasNormals != 0 ? vNormal : faceNormal;
  float len = length(n);
  n = len > 0.0 ? n / len : faceNormal;
  vec3 toEye = -vViewPosition;
  if (dot(n, toEye) < 0.0) n = -n;
  float diffuse = max(dot(n, uLight), 0.0);
  float rim = pow(1.0 - clamp(n.z, 0.0, 1.0), 3.0);
  vec3 w = max(vWeights, vec3(0.0));
  vec3 factor = vec3(max(0.0, 1.0 - w.x - w.y - w.z)) + w.x * texel(vSlots.x, vUv01.xy) +
                w.y * texel(vSlots.y, vUv01.zw) + w.z * texel(vSlots.z, vUv2);
  vec3 c = vColor * factor * (uAmbient + (1.0 - uAmbient) * diffuse) + vec3(uRim * rim);
  fragColor = vec4(srgb(c), 1.0);
}
)";

const char* const kPointVertex = R"(#version 330 core
layout(location = 0) in vec3 aPosition;
uniform mat4 uView;
uniform mat4 uProjection;
uniform float uPointSize;
void main() {
  gl_Position = uProjection * (uView * vec4(aPosition, 1.0));
  gl_Position.z -= 0.0005 * gl_Position.w;  // in front of the surface the particle sits on
  gl_PointSize = uPointSize;
}
)";

const char* const kPointFragment = R"(#version 330 core
out vec4 fragColor;
void main() {
  vec2 d = gl_PointCoord - vec2(0.5);
  if (dot(d, d) > 0.25) discard;  // round dots
  fragColor = vec4(1.0, 0.95, 0.35, 1.0);
}
)";

// The background: a quad covering the viewport whose two bottom and two top corners carry the gradient's end
// colours already sRGB-encoded, so the fragment shader only passes the interpolated colour on. Under a software
// rasterizer (llvmpipe) encoding every pixel cost ~4 ms of a 1280x720 frame; now the pass costs about what a clear
// does. Interpolating encoded colours instead of linear ones differs by at most 2/255 over this gradient.
const char* const kBackgroundVertex = "#version 330 core\n" IMPS_GLSL_SRGB R"(
uniform vec3 uTop;
uniform vec3 uBottom;
out vec3 vColor;
void main() {
  // A triangle strip of four corners from the vertex index alone: (-1,-1), (1,-1), (-1,1), (1,1).
  vec2 p = vec2(float(gl_VertexID & 1), float(gl_VertexID >> 1)) * 2.0 - 1.0;
  vColor = srgb(p.y > 0.0 ? uTop : uBottom);
  gl_Position = vec4(p, 0.0, 1.0);
}
)";

const char* const kBackgroundFragment = R"(#version 330 core
in vec3 vColor;
out vec4 fragColor;
void main() { fragColor = vec4(vColor, 1.0); }
)";

// The overlay: window-pixel positions, colours in linear light.
const char* const kOverlayVertex = "#version 330 core\n" IMPS_GLSL_SRGB R"(
layout(location = 0) in vec2 aPixel;
layout(location = 1) in vec3 aColor;
uniform vec2 uWindow;
out vec3 vColor;
void main() {
  vColor = srgb(aColor);
  gl_Position = vec4(aPixel.x / uWindow.x * 2.0 - 1.0, 1.0 - aPixel.y / uWindow.y * 2.0, 0.0, 1.0);
}
)";

// One corner of a textured triangle (the textured VAO's interleaved layout).
struct TexturedCorner {
  float position[3];
  float normal[3];
  float color[3];
  int32_t slots[3];
  float uv01[4];
  float uv2[2];
  float weights[3];
};

// Compiles and links one program; returns 0 and appends to `error` on failure.
GLuint buildProgram(const char* vertex, const char* fragment, const char* name, std::string& error) {
  auto compile = [&](GLenum type, const char* source) -> GLuint {
    const GLuint s = glCreateShader(type);
    glShaderSource(s, 1, &source, nullptr);
    glCompileShader(s);
    GLint ok = 0;
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
      char log[2048] = {};
      glGetShaderInfoLog(s, sizeof log, nullptr, log);
      error += std::string(name) + (type == GL_VERTEX_SHADER ? " vertex" : " fragment") + " shader: " + log;
      glDeleteShader(s);
      return 0;
    }
    return s;
  };
  const GLuint vs = compile(GL_VERTEX_SHADER, vertex), fs = compile(GL_FRAGMENT_SHADER, fragment);
  if (!vs || !fs) {
    if (vs) glDeleteShader(vs);
    if (fs) glDeleteShader(fs);
    return 0;
  }
  const GLuint program = glCreateProgram();
  glAttachShader(program, vs);
  glAttachShader(program, fs);
  glLinkProgram(program);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint ok = 0;
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[2048] = {};
    glGetProgramInfoLog(program, sizeof log, nullptr, log);
    error += std::string(name) + " program: " + log;
    glDeleteProgram(program);
    return 0;
  }
  return program;
}

// Orphans `buffer` (a fresh store of `bytes`) and fills it, so the GPU may still read last frame's store.
void orphanAndFill(GLenum target, GLuint buffer, const void* data, size_t bytes) {
  glBindBuffer(target, buffer);
  glBufferData(target, static_cast<GLsizeiptr>(bytes), nullptr, GL_STREAM_DRAW);
  if (bytes > 0) glBufferSubData(target, 0, static_cast<GLsizeiptr>(bytes), data);
}

void setMatrices(GLuint program, const glm::mat4& view, const glm::mat4& projection) {
  glUniformMatrix4fv(glGetUniformLocation(program, "uView"), 1, GL_FALSE, glm::value_ptr(view));
  glUniformMatrix4fv(glGetUniformLocation(program, "uProjection"), 1, GL_FALSE, glm::value_ptr(projection));
}

}  // namespace

Renderer::Renderer() {
  meshProgram_ = buildProgram(kMeshVertex, kMeshFragment, "mesh", error_);
  pointProgram_ = buildProgram(kPointVertex, kPointFragment, "particle", error_);
  backgroundProgram_ = buildProgram(kBackgroundVertex, kBackgroundFragment, "background", error_);
  overlayProgram_ = buildProgram(kOverlayVertex, kBackgroundFragment, "overlay", error_);
  glGenVertexArrays(1, &overlayVao_);
  glGenBuffers(1, &overlayBuffer_);
  glBindVertexArray(overlayVao_);
  glBindBuffer(GL_ARRAY_BUFFER, overlayBuffer_);
  glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, sizeof(OverlayVertex),
                        reinterpret_cast<const void*>(offsetof(OverlayVertex, pixel)));
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, sizeof(OverlayVertex),
                        reinterpret_cast<const void*>(offsetof(OverlayVertex, color)));
  glEnableVertexAttribArray(0);
  glEnableVertexAttribArray(1);
  glGenVertexArrays(1, &meshVao_);
  glGenVertexArrays(1, &pointVao_);
  glGenVertexArrays(1, &backgroundVao_);
  GLuint buffers[5];
  glGenBuffers(5, buffers);
  positionBuffer_ = buffers[0], normalBuffer_ = buffers[1], colorBuffer_ = buffers[2];
  indexBuffer_ = buffers[3], pointBuffer_ = buffers[4];

  glBindVertexArray(meshVao_);
  const GLuint attributeBuffers[3] = {positionBuffer_, normalBuffer_, colorBuffer_};
  for (GLuint a = 0; a < 3; ++a) {
    glBindBuffer(GL_ARRAY_BUFFER, attributeBuffers[a]);
    glVertexAttribPointer(a, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
  }
  glEnableVertexAttribArray(0);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, indexBuffer_);  // recorded in the VAO
  glBindVertexArray(pointVao_);
  glBindBuffer(GL_ARRAY_BUFFER, pointBuffer_);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
  glEnableVertexAttribArray(0);

  texturedProgram_ = buildProgram(kTexturedVertex, kTexturedFragment, "textured mesh", error_);
  glGenVertexArrays(1, &texturedVao_);
  glGenBuffers(1, &texturedBuffer_);
  glBindVertexArray(texturedVao_);
  glBindBuffer(GL_ARRAY_BUFFER, texturedBuffer_);
  const auto stride = static_cast<GLsizei>(sizeof(TexturedCorner));
  auto at = [](size_t offset) { return reinterpret_cast<const void*>(offset); };
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, stride, at(offsetof(TexturedCorner, position)));
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, stride, at(offsetof(TexturedCorner, normal)));
  glVertexAttribPointer(2, 3, GL_FLOAT, GL_FALSE, stride, at(offsetof(TexturedCorner, color)));
  glVertexAttribIPointer(3, 3, GL_INT, stride, at(offsetof(TexturedCorner, slots)));
  glVertexAttribPointer(4, 4, GL_FLOAT, GL_FALSE, stride, at(offsetof(TexturedCorner, uv01)));
  glVertexAttribPointer(5, 2, GL_FLOAT, GL_FALSE, stride, at(offsetof(TexturedCorner, uv2)));
  glVertexAttribPointer(6, 3, GL_FLOAT, GL_FALSE, stride, at(offsetof(TexturedCorner, weights)));
  for (GLuint a = 0; a < 7; ++a) glEnableVertexAttribArray(a);
  glBindVertexArray(0);
}

Renderer::~Renderer() {
  const GLuint buffers[5] = {positionBuffer_, normalBuffer_, colorBuffer_, indexBuffer_, pointBuffer_};
  glDeleteBuffers(5, buffers);
  const GLuint arrays[3] = {meshVao_, pointVao_, backgroundVao_};
  glDeleteVertexArrays(3, arrays);
  glDeleteBuffers(1, &overlayBuffer_);
  glDeleteVertexArrays(1, &overlayVao_);
  for (GLuint p : {meshProgram_, pointProgram_, backgroundProgram_, overlayProgram_, texturedProgram_})
    if (p) glDeleteProgram(p);
  glDeleteBuffers(1, &texturedBuffer_);
  glDeleteVertexArrays(1, &texturedVao_);
  if (textureArray_) glDeleteTextures(1, &textureArray_);
}

void Renderer::uploadTextures(const std::vector<RgbaImage>& images) {
  if (textureArray_) glDeleteTextures(1, &textureArray_);
  textureArray_ = 0;
  textureLayers_ = 0;
  int width = 1, height = 1;
  for (const RgbaImage& image : images) {
    width = std::max(width, image.width);
    height = std::max(height, image.height);
  }
  if (images.empty()) return;
  glGenTextures(1, &textureArray_);
  glBindTexture(GL_TEXTURE_2D_ARRAY, textureArray_);
  glTexImage3D(GL_TEXTURE_2D_ARRAY, 0, GL_SRGB8_ALPHA8, width, height, GLsizei(images.size()), 0, GL_RGBA,
               GL_UNSIGNED_BYTE, nullptr);
  std::vector<uint8_t> resampled(size_t(width) * size_t(height) * 4);
  for (size_t layer = 0; layer < images.size(); ++layer) {
    const RgbaImage& image = images[layer];
    const uint8_t* pixels = image.rgba.data();
    if (image.width != width || image.height != height) {
      // Bilinear resampling in the image's own (sRGB) bytes: good enough for a texture that is then mipmapped.
      for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
          uint8_t* d = &resampled[(size_t(y) * size_t(width) + size_t(x)) * 4];
          if (image.width <= 0 || image.height <= 0) {
            std::fill_n(d, 4, uint8_t(255));
            continue;
          }
          const float sx =
              std::clamp((float(x) + 0.5f) * float(image.width) / float(width) - 0.5f, 0.0f, float(image.width - 1));
          const float sy =
              std::clamp((float(y) + 0.5f) * float(image.height) / float(height) - 0.5f, 0.0f, float(image.height - 1));
          const int x0 = int(sx), y0 = int(sy), x1 = std::min(x0 + 1, image.width - 1),
                    y1 = std::min(y0 + 1, image.height - 1);
          const float ax = sx - float(x0), ay = sy - float(y0);
          for (int ch = 0; ch < 4; ++ch) {
            auto p = [&](int i, int j) {
              return float(image.rgba[(size_t(j) * size_t(image.width) + size_t(i)) * 4 + size_t(ch)]);
            };
            const float v =
                (1 - ay) * ((1 - ax) * p(x0, y0) + ax * p(x1, y0)) + ay * ((1 - ax) * p(x0, y1) + ax * p(x1, y1));
            d[ch] = uint8_t(std::clamp(v + 0.5f, 0.0f, 255.0f));
          }
        }
      pixels = resampled.data();
    }
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTexSubImage3D(GL_TEXTURE_2D_ARRAY, 0, 0, 0, GLint(layer), width, height, 1, GL_RGBA, GL_UNSIGNED_BYTE, pixels);
  }
  glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_S, GL_REPEAT);
  glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_T, GL_REPEAT);
  glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
  glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glGenerateMipmap(GL_TEXTURE_2D_ARRAY);
  glBindTexture(GL_TEXTURE_2D_ARRAY, 0);
  textureLayers_ = int32_t(images.size());
}

void Renderer::uploadMesh(const Mesh& mesh) {
  texturedCount_ = 0;
  if (mesh.textured()) {
    uploadTexturedMesh(mesh);
    indexCount_ = 0;
    return;
  }
  glBindVertexArray(meshVao_);
  orphanAndFill(GL_ARRAY_BUFFER, positionBuffer_, mesh.positions.data(), mesh.positions.size() * sizeof(float));
  meshHasNormals_ = !mesh.normals.empty();
  meshHasColors_ = !mesh.colors.empty();
  if (meshHasNormals_) {
    orphanAndFill(GL_ARRAY_BUFFER, normalBuffer_, mesh.normals.data(), mesh.normals.size() * sizeof(float));
    glEnableVertexAttribArray(1);
  } else {
    glDisableVertexAttribArray(1);
  }
  if (meshHasColors_) {
    orphanAndFill(GL_ARRAY_BUFFER, colorBuffer_, mesh.colors.data(), mesh.colors.size() * sizeof(float));
    glEnableVertexAttribArray(2);
  } else {
    glDisableVertexAttribArray(2);
  }
  orphanAndFill(GL_ELEMENT_ARRAY_BUFFER, indexBuffer_, mesh.indices.data(), mesh.indices.size() * sizeof(uint32_t));
  indexCount_ = static_cast<int32_t>(mesh.indices.size());
  glBindVertexArray(0);
}

void Renderer::uploadTexturedMesh(const Mesh& mesh) {
  thread_local std::vector<TexturedCorner> corners;
  corners.resize(mesh.indices.size());
  TriangleLayers layers;
  const bool hasNormals = !mesh.normals.empty(), hasColors = !mesh.colors.empty();
  meshHasNormals_ = hasNormals;
  for (size_t t = 0; t < mesh.triangleCount(); ++t) {
    const uint32_t* v = &mesh.indices[3 * t];
    layers.gather(mesh, v[0], v[1], v[2]);
    // The three heaviest layers (summed over the corners), heaviest first.
    const int count = std::clamp(layers.count, 0, TriangleLayers::kMax);
    int order[TriangleLayers::kMax] = {0, 1, 2, 3, 4, 5};
    auto total = [&](int i) { return layers.weight[i].x + layers.weight[i].y + layers.weight[i].z; };
    // Insertion sort: at most six layers (and GCC 12's -Warray-bounds misreads std::sort on a fixed array).
    for (int i = 1; i < count; ++i)
      for (int j = i; j > 0 && total(order[j]) > total(order[j - 1]); --j) std::swap(order[j], order[j - 1]);
    for (int k = 0; k < 3; ++k) {
      TexturedCorner& c = corners[3 * t + size_t(k)];
      const glm::vec3 p = mesh.position(v[k]);
      const glm::vec3 n = hasNormals ? mesh.normal(v[k]) : glm::vec3(0.0f);
      const glm::vec3 col = hasColors ? mesh.color(v[k]) : look_.defaultColor;
      std::memcpy(c.position, &p, sizeof c.position);
      std::memcpy(c.normal, &n, sizeof c.normal);
      std::memcpy(c.color, &col, sizeof c.color);
      float uv[6] = {};
      for (int s = 0; s < 3; ++s) {
        const bool used = s < count;
        const int i = used ? order[s] : 0;
        const int32_t image = used ? layers.image[i] : -1;
        c.slots[s] = image >= 0 && image < textureLayers_ ? image : -1;
        c.weights[s] = used ? layers.weight[i][k] : 0.0f;
        uv[2 * s] = used ? layers.uv[i][k].x : 0.0f;
        uv[2 * s + 1] = used ? layers.uv[i][k].y : 0.0f;
      }
      std::memcpy(c.uv01, uv, sizeof c.uv01);
      std::memcpy(c.uv2, uv + 4, sizeof c.uv2);
    }
  }
  glBindVertexArray(texturedVao_);
  orphanAndFill(GL_ARRAY_BUFFER, texturedBuffer_, corners.data(), corners.size() * sizeof(TexturedCorner));
  glBindVertexArray(0);
  texturedCount_ = static_cast<int32_t>(corners.size());
}

void Renderer::uploadParticles(std::span<const glm::vec3> positions) {
  orphanAndFill(GL_ARRAY_BUFFER, pointBuffer_, positions.data(), positions.size_bytes());
  pointCount_ = static_cast<int32_t>(positions.size());
}

void Renderer::draw(const Camera& camera, int width, int height, bool particles) {
  glViewport(0, 0, width, height);
  glDisable(GL_BLEND);
  glDisable(GL_SCISSOR_TEST);
  glDisable(GL_CULL_FACE);
  glDepthMask(GL_TRUE);
  glClear(GL_DEPTH_BUFFER_BIT);  // the background below covers every pixel's colour

  // Background gradient, behind everything.
  glDisable(GL_DEPTH_TEST);
  glUseProgram(backgroundProgram_);
  glUniform3fv(glGetUniformLocation(backgroundProgram_, "uTop"), 1, glm::value_ptr(look_.backgroundTop));
  glUniform3fv(glGetUniformLocation(backgroundProgram_, "uBottom"), 1, glm::value_ptr(look_.backgroundBottom));
  glBindVertexArray(backgroundVao_);
  glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);

  const glm::mat4 view = camera.viewMatrix();
  const glm::mat4 projection =
      camera.projectionMatrix(static_cast<float>(width) / static_cast<float>(std::max(1, height)), sceneRadius_);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  if (texturedCount_ > 0) {
    glUseProgram(texturedProgram_);
    setMatrices(texturedProgram_, view, projection);
    const glm::vec3 light = glm::normalize(look_.lightDirection);
    glUniform3fv(glGetUniformLocation(texturedProgram_, "uLight"), 1, glm::value_ptr(light));
    glUniform1f(glGetUniformLocation(texturedProgram_, "uAmbient"), look_.ambient);
    glUniform1f(glGetUniformLocation(texturedProgram_, "uRim"), look_.rim);
    glUniform1i(glGetUniformLocation(texturedProgram_, "uHasNormals"), meshHasNormals_ ? 1 : 0);
    glUniform1i(glGetUniformLocation(texturedProgram_, "uTextures"), 0);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D_ARRAY, textureArray_);
    glBindVertexArray(texturedVao_);
    glDrawArrays(GL_TRIANGLES, 0, texturedCount_);
    glBindTexture(GL_TEXTURE_2D_ARRAY, 0);
  }
  if (indexCount_ > 0) {
    glUseProgram(meshProgram_);
    setMatrices(meshProgram_, view, projection);
    const glm::vec3 light = glm::normalize(look_.lightDirection);
    glUniform3fv(glGetUniformLocation(meshProgram_, "uLight"), 1, glm::value_ptr(light));
    glUniform1f(glGetUniformLocation(meshProgram_, "uAmbient"), look_.ambient);
    glUniform1f(glGetUniformLocation(meshProgram_, "uRim"), look_.rim);
    glUniform1i(glGetUniformLocation(meshProgram_, "uHasNormals"), meshHasNormals_ ? 1 : 0);
    glBindVertexArray(meshVao_);
    if (!meshHasColors_) glVertexAttrib3fv(2, glm::value_ptr(look_.defaultColor));
    glDrawElements(GL_TRIANGLES, indexCount_, GL_UNSIGNED_INT, nullptr);
  }
  if (particles && pointCount_ > 0) {
    glEnable(GL_PROGRAM_POINT_SIZE);
    glUseProgram(pointProgram_);
    setMatrices(pointProgram_, view, projection);
    glUniform1f(glGetUniformLocation(pointProgram_, "uPointSize"),
                pointSize_ > 0.0f ? pointSize_ : height >= 600 ? 4.0f : 3.0f);
    glBindVertexArray(pointVao_);
    glDrawArrays(GL_POINTS, 0, pointCount_);
  }
  glBindVertexArray(0);
  glUseProgram(0);
}

void Renderer::drawOverlay(std::span<const OverlayVertex> triangles, int width, int height) {
  if (triangles.empty()) return;
  glViewport(0, 0, width, height);
  glDisable(GL_DEPTH_TEST);
  glUseProgram(overlayProgram_);
  glUniform2f(glGetUniformLocation(overlayProgram_, "uWindow"), float(std::max(1, width)), float(std::max(1, height)));
  glBindVertexArray(overlayVao_);
  orphanAndFill(GL_ARRAY_BUFFER, overlayBuffer_, triangles.data(), triangles.size_bytes());
  glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(triangles.size()));
  glBindVertexArray(0);
  glUseProgram(0);
}

std::vector<uint8_t> Renderer::readPixels(int width, int height) {
  const size_t rowBytes = static_cast<size_t>(width) * 4;
  std::vector<uint8_t> pixels(rowBytes * static_cast<size_t>(height));
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadBuffer(GL_BACK);
  glReadPixels(0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, pixels.data());
  // GL's rows start at the bottom.
  std::vector<uint8_t> row(rowBytes);
  for (size_t y = 0; y < static_cast<size_t>(height) / 2; ++y) {
    uint8_t* a = pixels.data() + y * rowBytes;
    uint8_t* b = pixels.data() + (static_cast<size_t>(height) - 1 - y) * rowBytes;
    std::memcpy(row.data(), a, rowBytes);
    std::memcpy(a, b, rowBytes);
    std::memcpy(b, row.data(), rowBytes);
  }
  for (size_t i = 3; i < pixels.size(); i += 4) pixels[i] = 255;
  return pixels;
}

}  // namespace imps::app
