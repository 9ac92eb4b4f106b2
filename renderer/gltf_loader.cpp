#include "renderer/gltf_loader.h"

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <stb/stb_image.h>
#include <tbb/parallel_for.h>
#include <tiny_gltf.h>

#include <Eigen/SVD>

#include <algorithm>
#include <optional>
#include <functional>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <tuple>
#include <type_traits>
#include <unistd.h>

#include "renderer/draco_mesh.h"
#include "renderer/gltf_json_check.h"
#include "renderer/mesh_attributes.h"
#include "renderer/meshopt_buffer.h"
#include "util/error.h"
#include "util/image.h"
#include "util/parse.h"

// tinygltf's base64 decoder: libtinygltf exports it, its header declares it only to the library's
// own implementation.
namespace tinygltf {
std::string base64_decode(std::string const& encoded);
}

namespace dynsky {

Eigen::Matrix3f texture_transform_matrix(const Vec2& offset, float rotation, const Vec2& scale) {
    Eigen::Matrix3f t = Eigen::Matrix3f::Identity(), r = Eigen::Matrix3f::Identity(), s = Eigen::Matrix3f::Identity();
    t(0, 2) = offset.x(), t(1, 2) = offset.y();
    float c = std::cos(rotation), sn = std::sin(rotation);
    // The extension's GLSL listing writes this matrix column-major, which read literally is the
    // transpose; its prose ("counter-clockwise") and its worked example (offset [0, 1], rotation
    // pi/2, scale 0.5 selects the lower-left quadrant) need this form, as three.js and other
    // viewers implement it.
    r(0, 0) = c, r(0, 1) = sn, r(1, 0) = -sn, r(1, 1) = c;
    s(0, 0) = scale.x(), s(1, 1) = scale.y();
    return t * r * s;
}

namespace {

namespace tg = tinygltf;

// Input limits (docs/input-limits.md).
constexpr size_t kMaxJsonDepth = 256;               // nesting of JSON objects and arrays
constexpr double kMinTransformDeterminant = 1e-30;  // |det| of a world transform's 3x3 part, and 1 / it
// An accessor without a bufferView is zeros (plus sparse values): it may hold at most as many
// elements as the file's buffers hold bytes, plus this many.
constexpr size_t kZeroAccessorSlack = size_t(1) << 20;

// Extensions whose meaning the loader fully implements (KHR_mesh_quantization only widens the
// accessor types allowed for attributes, which the accessor reader handles anyway).
const std::set<std::string>& supported_extensions() {
    static const std::set<std::string> s = {"KHR_texture_transform",      "KHR_materials_emissive_strength",
                                            "KHR_materials_transmission", "KHR_materials_clearcoat",
                                            "EXT_mesh_gpu_instancing",    "KHR_mesh_quantization",
                                            "KHR_lights_punctual",        "KHR_materials_ior",
                                            "KHR_materials_volume",       "EXT_texture_webp",
                                            "KHR_materials_sheen",        "KHR_materials_specular",
                                            "KHR_draco_mesh_compression", "EXT_meshopt_compression",
                                            "KHR_materials_unlit",        "KHR_materials_pbrSpecularGlossiness",
                                            "KHR_materials_anisotropy"};
    return s;
}

// Extensions that carry no meaning for a render (licence and authoring metadata, a promise that
// meshes are closed): accepted without a word, as newer Khronos sample files all use the first.
const std::set<std::string>& metadata_extensions() {
    static const std::set<std::string> s = {"KHR_xmp_json_ld", "KHR_xmp", "EXT_mesh_manifold"};
    return s;
}

std::string in_quotes(const std::string& s) { return "'" + s + "'"; }

// Trims and joins tinygltf's newline-separated messages.
std::vector<std::string> split_lines(const std::string& text) {
    std::vector<std::string> lines;
    std::istringstream in(text);
    std::string line;
    while (std::getline(in, line)) {
        size_t a = line.find_first_not_of(" \t\r"), b = line.find_last_not_of(" \t\r");
        if (a != std::string::npos) lines.push_back(line.substr(a, b - a + 1));
    }
    return lines;
}

std::string join(const std::vector<std::string>& parts, const std::string& sep) {
    std::string out;
    for (size_t i = 0; i < parts.size(); ++i) out += (i ? sep : "") + parts[i];
    return out;
}

// What a file that is not glTF looks like, for the error message.
std::string describe_foreign_bytes(const std::vector<unsigned char>& b) {
    auto starts = [&](const char* sig, size_t n) { return b.size() >= n && std::memcmp(b.data(), sig, n) == 0; };
    if (b.empty()) return "the file is empty";
    if (starts("\x89PNG", 4)) return "not a glTF file: it is a PNG image";
    if (starts("\xFF\xD8\xFF", 3)) return "not a glTF file: it is a JPEG image";
    if (starts("\x76\x2F\x31\x01", 4)) return "not a glTF file: it is an OpenEXR image";
    return "not a glTF file: no binary 'glTF' magic and not a JSON object";
}

uint32_t read_u32(const unsigned char* p) {
    return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
}

// The deepest nesting of JSON objects and arrays, strings skipped. JSON parsers recurse once per
// level, so a file nested 20,000 deep overflows the stack: it is measured before any parsing.
size_t json_depth(const char* text, size_t size) {
    size_t depth = 0, deepest = 0;
    bool in_string = false;
    for (size_t i = 0; i < size; ++i) {
        char c = text[i];
        if (in_string) {
            if (c == '\\') ++i;
            else if (c == '"') in_string = false;
        } else if (c == '"') {
            in_string = true;
        } else if (c == '{' || c == '[') {
            deepest = std::max(deepest, ++depth);
        } else if ((c == '}' || c == ']') && depth > 0) {
            --depth;
        }
    }
    return deepest;
}

// The size an encoded image's header declares: a PNG's IHDR read directly (stb gives up on
// headers beyond its own limit, which then went unchecked to libpng: a 16385^2 PNG of zeros took
// 5.4 GB), anything else through stb. False when it cannot tell.
bool is_png(const unsigned char* b, size_t n) {
    static const unsigned char signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    return n >= 8 && std::memcmp(b, signature, 8) == 0;
}

// RIFF....WEBP: a WebP image (EXT_texture_webp).
bool is_webp(const unsigned char* b, size_t n) {
    return n >= 12 && std::memcmp(b, "RIFF", 4) == 0 && std::memcmp(b + 8, "WEBP", 4) == 0;
}

// A WebP's canvas from its first chunk (VP8X: 24-bit sizes minus one; VP8L: 14-bit sizes minus one
// after the 0x2f signature; VP8: 14-bit sizes after the key frame's start code).
bool webp_header_size(const unsigned char* b, size_t n, long long* width, long long* height) {
    if (n < 30) return false;
    const auto le = [&](size_t at, int bytes) {
        uint32_t v = 0;
        for (int k = bytes - 1; k >= 0; --k) v = (v << 8) | b[at + size_t(k)];
        return v;
    };
    if (std::memcmp(b + 12, "VP8X", 4) == 0) {
        *width = le(24, 3) + 1LL, *height = le(27, 3) + 1LL;
        return true;
    }
    if (std::memcmp(b + 12, "VP8L", 4) == 0 && b[20] == 0x2f) {
        const uint32_t bits = le(21, 4);
        *width = (bits & 0x3fff) + 1LL, *height = ((bits >> 14) & 0x3fff) + 1LL;
        return true;
    }
    if (std::memcmp(b + 12, "VP8 ", 4) == 0 && b[23] == 0x9d && b[24] == 0x01 && b[25] == 0x2a) {
        *width = le(26, 2) & 0x3fff, *height = le(28, 2) & 0x3fff;
        return true;
    }
    return false;
}

// A PNG's big-endian 32-bit number (chunk lengths, IHDR's width and height) at b.
uint32_t png_uint32(const unsigned char* b) {
    return (uint32_t(b[0]) << 24) | (uint32_t(b[1]) << 16) | (uint32_t(b[2]) << 8) | b[3];
}

bool image_header_size(const unsigned char* b, size_t n, long long* width, long long* height) {
    if (is_webp(b, n)) return webp_header_size(b, n, width, height);
    if (n >= 24 && is_png(b, n)) {
        *width = png_uint32(b + 16), *height = png_uint32(b + 20);
        return true;
    }
    int w = 0, h = 0, c = 0;
    if (n > size_t(std::numeric_limits<int>::max()) || !stbi_info_from_memory(b, int(n), &w, &h, &c)) return false;
    *width = w, *height = h;
    return true;
}

// Whether a PNG is grey (colour type 0) with a tRNS chunk: one grey value that is transparent.
// OpenCV decodes it to one channel and drops the key (a cut-out mask came out opaque).
bool is_grey_png_with_key_colour(const unsigned char* b, size_t n) {
    if (n < 33 || !is_png(b, n) || b[25] != 0) return false;
    for (size_t at = 8; at + 8 <= n;) {
        const size_t length = png_uint32(b + at);
        const std::string type(reinterpret_cast<const char*>(b + at + 4), 4);
        if (type == "tRNS") return true;
        if (type == "IDAT" || type == "IEND") return false;  // tRNS comes before the image data
        at += 12 + length;
    }
    return false;
}

// A PNG decoded to RGBA in [0, 1] (8- or 16-bit; grey, grey + alpha, palette, RGB, RGBA): "" or why not.
// Decodes a PNG or WebP (`format` names it in messages) through OpenCV into float RGBA.
std::string decode_with_opencv(const unsigned char* bytes, size_t size, const std::string& format, int* width,
                               int* height, std::vector<float>* rgba) {
    if (size > size_t(std::numeric_limits<int>::max())) return "a " + format + " too large to decode";
    cv::Mat image;
    try {
        image = cv::imdecode(cv::Mat(1, int(size), CV_8U, const_cast<unsigned char*>(bytes)), cv::IMREAD_UNCHANGED);
    } catch (const cv::Exception& e) {
        return "a " + format + " that cannot be decoded (" + e.err + ")";
    }
    if (image.empty())
        return "a " + format + " that cannot be decoded (corrupt or cut short" +
               (format == "PNG" ? std::string(": a chunk's CRC or the compressed data is wrong)") : std::string(")"));
    const int c = image.channels();
    if ((image.depth() != CV_8U && image.depth() != CV_16U) || c < 1 || c > 4) return "unexpected decoded layout";
    *width = image.cols, *height = image.rows;
    rgba->resize(size_t(image.cols) * size_t(image.rows) * 4);
    // The same values stb's path gives: v x (1 / 255) or v x (1 / 65535) in float.
    auto convert = [&](auto max_value, auto* row_type) {
        using T = std::remove_pointer_t<decltype(row_type)>;
        const float unit = 1.0f / float(max_value);
        float* out = rgba->data();
        for (int y = 0; y < image.rows; ++y) {
            const T* row = image.ptr<T>(y);
            for (int x = 0; x < image.cols; ++x, out += 4) {
                const T* px = row + size_t(x) * size_t(c);
                if (c <= 2) {  // grey (and alpha)
                    out[0] = out[1] = out[2] = float(px[0]) * unit;
                    out[3] = float(c == 2 ? px[1] : max_value) * unit;
                } else {  // OpenCV's BGR(A)
                    out[0] = float(px[2]) * unit, out[1] = float(px[1]) * unit, out[2] = float(px[0]) * unit;
                    out[3] = float(c == 4 ? px[3] : max_value) * unit;
                }
            }
        }
    };
    if (image.depth() == CV_8U) convert(255, static_cast<const uint8_t*>(nullptr));
    else convert(65535, static_cast<const uint16_t*>(nullptr));
    return "";
}

// Why a buffer or image URI may not be opened ("" when it may): it must name a file inside the
// asset's folder, by a relative path that does not climb out of it.
std::string uri_problem(const std::string& uri) {
    if (uri.rfind("data:", 0) == 0) return "";
    const std::string path = percent_decoded(uri);
    static const std::regex scheme("^[A-Za-z][A-Za-z0-9+.-]*:.*");
    if (path.empty()) return "is empty";
    // tinygltf decodes a '%' without two hex digits after it into arbitrary bytes (%zz became a NUL
    // that cut the name short: "scene%zz.bin" opened the file "scene").
    for (size_t i = 0; i < uri.size(); ++i)
        if (uri[i] == '%' && !(i + 2 < uri.size() && std::isxdigit((unsigned char)uri[i + 1]) &&
                               std::isxdigit((unsigned char)uri[i + 2])))
            return "has a '%' not followed by two hex digits (an invalid percent escape): write it as %25";
    if (path.find('\0') != std::string::npos)
        return "contains a NUL byte (%00): it would name another file than it says";
    for (char c : path)
        if ((unsigned char)c < 0x20 || c == 0x7f) return "contains a control character: not a file name";
    if (path[0] == '/' || path[0] == '\\' || std::regex_match(path, scheme))
        return "is an absolute path or URL: glTF files may only refer to files inside their own folder";
    std::filesystem::path normal = std::filesystem::path(path).lexically_normal();
    if (!normal.empty() && *normal.begin() == "..")
        return "leaves the asset's folder ('..'): glTF files may only refer to files inside their own folder";
    return "";
}

// True when `inner` is `folder` or lies below it (both absolute and normalised).
bool is_inside(const std::filesystem::path& inner, const std::filesystem::path& folder) {
    auto f = folder.begin(), i = inner.begin();
    for (; f != folder.end(); ++f, ++i) {
        if (f->empty() && std::next(f) == folder.end()) break;  // a trailing separator
        if (i == inner.end() || *i != *f) return false;
    }
    return true;
}

// The largest emissive strength read: a million (a bright lamp is 10-1000); beyond it a file is
// broken, and 1e39 is infinite in single precision.
constexpr double kMaxEmissiveStrength = 1e6;

// The file callbacks given to tinygltf for buffers and images: each file must lie inside the
// asset's folder once symbolic links are resolved, and be a regular file (a FIFO would block
// forever, a directory ends in bad_alloc). The first refusal is kept for the error message.
struct AssetFolder {
    std::filesystem::path folder;    // absolute, canonical (links resolved)
    std::filesystem::path as_given;  // absolute, lexically normal (as tinygltf joins paths to it)
    std::string refusal;
    std::vector<std::string> read;  // the files read (canonical)
};

bool asset_file_exists(const std::string& path, void* user) {
    namespace fs = std::filesystem;
    const auto* asset = static_cast<const AssetFolder*>(user);
    std::error_code ec;
    // tinygltf also tries the working directory: only files inside the asset's folder count.
    fs::path p = fs::absolute(path, ec).lexically_normal();
    return !ec && is_inside(p, asset->as_given) && fs::exists(p, ec);
}

std::string asset_expand_path(const std::string& path, void*) { return path; }  // no shell expansion

bool asset_read_file(std::vector<unsigned char>* out, std::string* err, const std::string& path, void* user) {
    namespace fs = std::filesystem;
    auto* asset = static_cast<AssetFolder*>(user);
    auto refuse = [&](const std::string& problem) {
        if (asset->refusal.empty()) asset->refusal = problem;
        if (err) *err += problem;
        return false;
    };
    std::error_code ec;
    fs::path real = fs::canonical(path, ec);
    if (ec) return refuse("URI target '" + path + "' cannot be resolved: " + ec.message());
    if (!is_inside(real, asset->folder))
        return refuse("URI target '" + path + "' resolves to " + real.string() + ", outside the asset's folder " +
                      asset->folder.string() + " (a symbolic link out?): refused");
    if (!fs::is_regular_file(real, ec))
        return refuse("URI target '" + path + "' is not a regular file (a directory, a FIFO or a device): refused");
    uintmax_t size = fs::file_size(real, ec);
    if (ec || size > std::numeric_limits<unsigned int>::max())
        return refuse("URI target '" + path + "' is larger than 4 GiB or unreadable: refused");
    std::ifstream in(real, std::ios::binary);
    out->resize(size_t(size));
    if (!in || !in.read(reinterpret_cast<char*>(out->data()), std::streamsize(size)))
        return refuse("URI target '" + path + "' cannot be read: " + std::strerror(errno));
    asset->read.push_back(real.string());
    return true;
}

bool asset_write_file(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
    if (err) *err += "dynsky never writes glTF files";
    return false;
}

// Whether a node's world transform collapses what it places to a point or a line (every axis, or
// all but one, scaled to 0): it shows nothing, and is how animations hide objects (a scale keyed
// to 0). Such a node is skipped, not refused; a plane (one axis flattened) is still refused below.
bool transform_collapses(const Eigen::Matrix4d& world) {
    const Eigen::Matrix3d m = world.topLeftCorner<3, 3>();
    if (!m.allFinite()) return false;
    const Eigen::Vector3d s = Eigen::JacobiSVD<Eigen::Matrix3d>(m).singularValues();  // descending
    return s(0) == 0 || s(1) <= 1e-7 * s(0);
}

// Why a node's world transform cannot instance geometry ("" when it can): Embree stores it in
// single precision and inverts it, so it must be finite there and far from singular.
std::string transform_problem(const Eigen::Matrix4d& world) {
    Eigen::Matrix<double, 3, 4> m = world.topRows<3>().cast<float>().cast<double>();
    if (!m.allFinite()) return "is not finite (NaN, infinite, or beyond single precision)";
    double det = m.leftCols<3>().determinant();
    if (!(std::abs(det) >= kMinTransformDeterminant && std::abs(det) <= 1.0 / kMinTransformDeterminant)) {
        return "is singular or degenerate (determinant " + number_text(det, 3) +
               ", outside 1e-30..1e30: a zero or flattened scale?)";
    }
    return "";
}

// The image callback given to tinygltf: keep the encoded bytes and decode later, in parallel and
// only for images a material uses. Images in a bufferView are read later from the (validated)
// view, so tinygltf's unchecked pointer into the buffer is never dereferenced.
bool keep_encoded_image(tg::Image* image, const int, std::string*, std::string*, int, int, const unsigned char* bytes,
                        int size, void*) {
    if (image->bufferView >= 0) return true;
    image->image.assign(bytes, bytes + std::max(size, 0));
    image->as_is = true;
    return true;
}

int component_count(int type) {
    switch (type) {
        case TINYGLTF_TYPE_SCALAR: return 1;
        case TINYGLTF_TYPE_VEC2: return 2;
        case TINYGLTF_TYPE_VEC3: return 3;
        case TINYGLTF_TYPE_VEC4: return 4;
        case TINYGLTF_TYPE_MAT2: return 4;
        case TINYGLTF_TYPE_MAT3: return 9;
        case TINYGLTF_TYPE_MAT4: return 16;
        default: return 0;
    }
}

const char* type_name(int type) {
    switch (type) {
        case TINYGLTF_TYPE_SCALAR: return "SCALAR";
        case TINYGLTF_TYPE_VEC2: return "VEC2";
        case TINYGLTF_TYPE_VEC3: return "VEC3";
        case TINYGLTF_TYPE_VEC4: return "VEC4";
        case TINYGLTF_TYPE_MAT2: return "MAT2";
        case TINYGLTF_TYPE_MAT3: return "MAT3";
        case TINYGLTF_TYPE_MAT4: return "MAT4";
        default: return "unknown";
    }
}

size_t component_size(int component_type) {
    switch (component_type) {
        case TINYGLTF_COMPONENT_TYPE_BYTE:
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
        case TINYGLTF_COMPONENT_TYPE_SHORT:
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
        case TINYGLTF_COMPONENT_TYPE_FLOAT: return 4;
        default: return 0;  // INT and DOUBLE are not glTF 2.0 accessor types
    }
}

// One component to the output type; normalised integers per glTF 2.0 section 3.11.
template <typename Out, typename C>
Out convert_component(C v, bool normalized) {
    if constexpr (std::is_same_v<Out, uint32_t>) {
        return uint32_t(v);
    } else if constexpr (std::is_floating_point_v<C>) {
        return Out(v);
    } else {
        if (!normalized) return Out(v);
        if constexpr (std::is_signed_v<C>) return std::max(float(v) / float(std::numeric_limits<C>::max()), -1.0f);
        else return Out(double(v) / double(std::numeric_limits<C>::max()));
    }
}

template <typename Out, typename C>
void copy_typed(const unsigned char* src, size_t stride, size_t count, int ncomp, bool normalized, Out* dst) {
    for (size_t i = 0; i < count; ++i) {
        const unsigned char* e = src + i * stride;
        for (int c = 0; c < ncomp; ++c) {
            C v;
            std::memcpy(&v, e + size_t(c) * sizeof(C), sizeof(C));  // accessors need not be aligned
            dst[i * size_t(ncomp) + size_t(c)] = convert_component<Out, C>(v, normalized);
        }
    }
}

template <typename Out>
void copy_components(int component_type, const unsigned char* src, size_t stride, size_t count, int ncomp,
                     bool normalized, Out* dst) {
    switch (component_type) {
        case TINYGLTF_COMPONENT_TYPE_BYTE: return copy_typed<Out, int8_t>(src, stride, count, ncomp, normalized, dst);
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
            return copy_typed<Out, uint8_t>(src, stride, count, ncomp, normalized, dst);
        case TINYGLTF_COMPONENT_TYPE_SHORT: return copy_typed<Out, int16_t>(src, stride, count, ncomp, normalized, dst);
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
            return copy_typed<Out, uint16_t>(src, stride, count, ncomp, normalized, dst);
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
            return copy_typed<Out, uint32_t>(src, stride, count, ncomp, normalized, dst);
        case TINYGLTF_COMPONENT_TYPE_FLOAT: return copy_typed<Out, float>(src, stride, count, ncomp, normalized, dst);
    }
}

// tinygltf::Value helpers that never trip its debug asserts on unexpected JSON.
const tg::Value* member(const tg::Value& v, const char* key) { return v.Has(key) ? &v.Get(key) : nullptr; }
double number_or(const tg::Value* v, double fallback) { return v && v->IsNumber() ? v->GetNumberAsDouble() : fallback; }
Vec2 vec2_or(const tg::Value* v, const Vec2& fallback) {
    if (!v || !v->IsArray() || v->ArrayLen() != 2 || !v->Get(0).IsNumber() || !v->Get(1).IsNumber()) return fallback;
    return Vec2(float(v->Get(0).GetNumberAsDouble()), float(v->Get(1).GetNumberAsDouble()));
}
const tg::Value* extension(const tg::ExtensionMap& map, const char* name) {
    auto it = map.find(name);
    return it != map.end() && it->second.IsObject() ? &it->second : nullptr;
}

// How a node poses its mesh's vertices: morph weights (empty: none) and skin joint matrices (a
// joint's world transform x its inverse bind matrix; empty: not skinned).
struct VertexPose {
    std::vector<double> morph_weights;
    std::vector<Eigen::Matrix4d> joints;
};

// Vertex attribute and instancing arrays as floats: count elements of `components` each.
struct FloatArray {
    std::vector<float> values;
    size_t count = 0;
    int components = 0;
};

Eigen::Matrix4d trs_matrix(const Eigen::Vector3d& t, const Eigen::Quaterniond& r, const Eigen::Vector3d& s) {
    Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
    m.topLeftCorner<3, 3>() = r.toRotationMatrix() * s.asDiagonal();
    m.topRightCorner<3, 1>() = t;
    return m;
}

Eigen::Affine3f to_affine(const Eigen::Matrix4d& m) {
    Eigen::Affine3f a = Eigen::Affine3f::Identity();
    a.matrix().topRows<3>() = m.topRows<3>().cast<float>();
    return a;
}

}  // namespace

class GltfLoader {
  public:
    GltfLoader(std::string path, double animation_time, std::string animation = "")
        : path_(std::move(path)), animation_time_(animation_time), animation_(std::move(animation)) {}

    Scene load() {
        load_once();
        if (animation_time_ >= 0) pose_animations(animation_time_);
        traverse_nodes();
        check_extent();
        if (!model_.animations.empty() && animation_time_ < 0)
            warn(std::to_string(model_.animations.size()) +
                 " animation(s) not played: the scene is rendered in its rest pose (--anim-time T poses it at T s" +
                 (animation_.empty() ? std::string(")") : ", --animation " + animation_ + " picking which)"));
        scene_.warnings = warnings_;
        return std::move(scene_);
    }

    // Everything that does not hang on the nodes: the file read and checked, its buffers decoded, the
    // materials and textures built. load() goes on to pose and build the nodes once; AnimatedGltf
    // poses again and again (pose): the file's nodes put back at rest and posed at t, and only what
    // hangs on them built again (meshes with their skins and morph targets, instances, cameras,
    // lights), the materials and decoded textures shared. A pose is what load() gives for that time.
    void load_once() {
        scene_.source = path_;
        parse_file();
        check_version();
        check_extensions();
        decode_meshopt_views();
        validate_buffer_views();
        decode_draco_primitives();
        rest_nodes_ = model_.nodes;
        choose_animations();
        build_materials();
        build_textures();
    }
    Scene pose(double t) {
        model_.nodes = rest_nodes_;
        pose_animations(t);
        scene_.meshes.clear(), scene_.instances.clear(), scene_.cameras.clear(), scene_.lights.clear();
        group_of_mesh_.clear(), cameras_.clear();
        traverse_nodes();
        check_extent();
        scene_.warnings = warnings_;
        return scene_;
    }

  private:
    [[noreturn]] void fail(const std::string& problem) const { throw_file_error(path_, problem); }

    void warn(const std::string& message) {
        if (std::find(warnings_.begin(), warnings_.end(), message) == warnings_.end()) warnings_.push_back(message);
    }

    // ---- File -------------------------------------------------------------------------------

    std::vector<unsigned char> read_file() const {
        namespace fs = std::filesystem;
        std::error_code ec;
        if (!fs::exists(path_, ec)) fail("no such file");
        if (!fs::is_regular_file(path_, ec)) fail("not a regular file");
        std::ifstream in(path_, std::ios::binary | std::ios::ate);
        if (!in) fail(std::string("cannot open: ") + std::strerror(errno));
        std::streamoff size = in.tellg();
        if (size < 0) fail("cannot determine the file size");
        std::vector<unsigned char> bytes(static_cast<size_t>(size));
        in.seekg(0);
        if (!in.read(reinterpret_cast<char*>(bytes.data()), size)) fail("read error");
        return bytes;
    }

    void check_glb_header(const std::vector<unsigned char>& b) const {
        if (b.size() < 12)
            fail("truncated GLB: " + std::to_string(b.size()) + " bytes, shorter than the 12-byte header");
        uint32_t version = read_u32(&b[4]), length = read_u32(&b[8]);
        if (version != 2) fail("GLB container version " + std::to_string(version) + " (only glTF 2.0 is supported)");
        if (length > b.size())
            fail("truncated GLB: the header says " + std::to_string(length) + " bytes but the file has " +
                 std::to_string(b.size()));
        if (length < 20) fail("truncated GLB: no JSON chunk");
        uint32_t json_length = read_u32(&b[12]), json_type = read_u32(&b[16]);
        if (json_type != 0x4E4F534Au) fail("malformed GLB: the first chunk is not JSON");
        if (uint64_t(json_length) + 20 > length)
            fail("truncated GLB: the JSON chunk needs " + std::to_string(json_length) + " bytes, " +
                 std::to_string(length - 20) + " remain");
        if (uint64_t(json_length) + 20 + 8 <= length) {
            uint32_t bin_length = read_u32(&b[20 + json_length]);
            if (uint64_t(bin_length) + 28 + json_length > length)
                fail("truncated GLB: the BIN chunk needs " + std::to_string(bin_length) + " bytes, " +
                     std::to_string(length - 28 - json_length) + " remain");
        }
    }

    void parse_file() {
        std::vector<unsigned char> bytes = read_file();
        if (bytes.size() > std::numeric_limits<unsigned int>::max()) fail("file larger than 4 GiB");
        bool binary = bytes.size() >= 4 && std::memcmp(bytes.data(), "glTF", 4) == 0;
        if (!binary) {
            size_t first = 0;
            while (first < bytes.size() && std::isspace(bytes[first])) ++first;
            // UTF-8 byte order mark, which some exporters write before the JSON.
            if (first + 3 <= bytes.size() && bytes[first] == 0xEF && bytes[first + 1] == 0xBB &&
                bytes[first + 2] == 0xBF)
                first += 3;
            if (first >= bytes.size() || bytes[first] != '{') fail(describe_foreign_bytes(bytes));
        } else {
            check_glb_header(bytes);
        }
        const char* json = reinterpret_cast<const char*>(bytes.data()) + (binary ? 20 : 0);
        const size_t json_size = binary ? read_u32(&bytes[12]) : bytes.size();
        if (size_t depth = json_depth(json, json_size); depth > kMaxJsonDepth)
            fail("JSON nested " + std::to_string(depth) + " levels deep, more than the " +
                 std::to_string(kMaxJsonDepth) + " dynsky reads (a corrupt or hostile file?)");
        std::vector<PlusUri> plus_uris;
        {
            nlohmann::json document = nlohmann::json::parse(json, json + json_size, nullptr, false);
            check_uris(document);
            GltfJsonReport report = check_gltf_json(document);
            for (const std::string& w : report.warnings) warn(w);
            if (!report.error.empty()) fail(report.error);
            // Draco primitives' indices accessors have no bufferView (the indices are in the
            // compressed data), which Debian's tinygltf, built without draco, refuses: the
            // primitive's "indices" is dropped before tinygltf reads the file, and the decoded
            // indices take its place (decode_draco). meshopt's fallback buffers have no data
            // (tinygltf refuses or misreads them): a 4-byte stand-in, replaced by the decoded views.
            const bool draco = drop_draco_indices(&document), meshopt = stand_in_meshopt_fallbacks(&document);
            const bool plus = encode_literal_plus(&document, &plus_uris);
            if (draco || meshopt || plus) bytes = with_json(bytes, binary, document.dump());
        }

        namespace fs = std::filesystem;
        std::string base_dir = fs::path(path_).parent_path().string();
        std::error_code ec;
        const fs::path folder = base_dir.empty() ? fs::path(".") : fs::path(base_dir);
        AssetFolder asset{fs::canonical(folder, ec), fs::absolute(folder).lexically_normal(), "", {}};
        if (ec) fail("cannot resolve the file's folder: " + ec.message());
        if (!asset.as_given.has_filename()) asset.as_given = asset.as_given.parent_path();  // "dir/" -> "dir"
        tg::TinyGLTF gltf;
        gltf.SetImageLoader(&keep_encoded_image, nullptr);
        gltf.SetFsCallbacks(tg::FsCallbacks{&asset_file_exists, &asset_expand_path, &asset_read_file, &asset_write_file,
                                            &asset});
        std::string err, warn_text;
        bool ok = binary
                      ? gltf.LoadBinaryFromMemory(&model_, &err, &warn_text, bytes.data(), unsigned(bytes.size()),
                                                  base_dir)
                      : gltf.LoadASCIIFromString(&model_, &err, &warn_text, reinterpret_cast<const char*>(bytes.data()),
                                                 unsigned(bytes.size()), base_dir);
        // The URIs as written, for the messages below.
        for (const PlusUri& u : plus_uris) {
            if (u.image && u.index < model_.images.size()) model_.images[u.index].uri = u.uri;
            if (!u.image && u.index < model_.buffers.size()) model_.buffers[u.index].uri = u.uri;
        }
        if (!asset.refusal.empty()) fail(asset.refusal);
        scene_.source_files = {path_};
        scene_.source_files.insert(scene_.source_files.end(), asset.read.begin(), asset.read.end());
        if (!ok) {
            std::vector<std::string> lines = split_lines(err);
            // tinygltf quotes a data: URI it could not decode whole (megabytes for a real buffer).
            for (std::string& l : lines)
                if (size_t at = l.find("data:"); at != std::string::npos && l.size() > at + 80)
                    l = l.substr(0, at + 80) + "... (" + std::to_string(l.size() - at) + " characters)";
            std::string text = join(lines, "; ");
            if (text.find("parse_error") != std::string::npos || text.find("Failed to parse JSON") != std::string::npos)
                fail("invalid JSON: " + text);
            // tinygltf says "Failed to decode 'uri'" also for base64 that decodes, but to fewer
            // or more bytes than the buffer's byteLength.
            if (text.find("Failed to decode 'uri' : data:") != std::string::npos)
                fail(
                    "a buffer's data: URI does not decode to its byteLength (not base64, or the byteLength "
                    "is wrong): " +
                    text);
            for (const std::string& l : lines)
                if (l.rfind("File not found", 0) == 0) {
                    size_t colon = l.find(':');
                    std::string missing = colon == std::string::npos ? l : l.substr(colon + 1);
                    size_t a = missing.find_first_not_of(' ');
                    // Where it was looked for, as the missing texture's error says: a scene given
                    // through a link to the file resolves its buffers beside the link.
                    fail("missing file " + in_quotes(a == std::string::npos ? missing : missing.substr(a)) +
                         " (a buffer referenced by the glTF, looked for in " +
                         in_quotes(fs::absolute(folder).lexically_normal().string()) + ")");
                }
            fail("cannot load glTF: " + (text.empty() ? std::string("tinygltf failed without a message") : text));
        }
        decode_other_data_uris();
        // Missing external images are only warnings in tinygltf: build_textures() turns them into
        // errors when a material needs them. Keep other tinygltf warnings.
        for (const std::string& l : split_lines(warn_text))
            if (l.rfind("File not found", 0) != 0 &&
                l.find("Failed to load external 'uri' for image") == std::string::npos)
                warn("tinygltf: " + l);
    }

    // tinygltf decodes the data: URIs of PNG, JPEG, BMP and GIF images only: a WebP embedded as
    // data:image/webp;base64 (EXT_texture_webp, as gltf-transform writes it) was reported as a
    // missing file named after the URI. Any other base64 image is decoded here (the decoders then
    // name its format); a data: URI that is not base64 is refused as what it is.
    void decode_other_data_uris() {
        for (size_t i = 0; i < model_.images.size(); ++i) {
            tg::Image& img = model_.images[i];
            if (img.bufferView >= 0 || !img.image.empty() || img.uri.rfind("data:", 0) != 0) continue;
            const size_t comma = img.uri.find(',');
            const std::string head = img.uri.substr(0, std::min(comma, img.uri.size()));
            if (comma == std::string::npos || head.size() < 7 || head.compare(head.size() - 7, 7, ";base64") != 0)
                fail("image " + std::to_string(i) + ": its data: URI " +
                     in_quotes(head.size() > 80 ? head.substr(0, 80) + "..." : head) +
                     " is not base64 (glTF embeds images as data:MIME;base64,...)");
            const std::string bytes = tg::base64_decode(img.uri.substr(comma + 1));
            if (bytes.empty())
                fail("image " + std::to_string(i) + ": its data: URI " + in_quotes(head) + " holds no bytes");
            img.image.assign(bytes.begin(), bytes.end());
            img.as_is = true;
        }
    }

    // Every buffer and image URI, before tinygltf opens any: relative and inside the asset's folder.
    void check_uris(const nlohmann::json& j) const {
        if (!j.is_object()) return;  // tinygltf reports the syntax error
        for (const char* kind : {"buffers", "images"}) {
            auto list = j.find(kind);
            if (list == j.end() || !list->is_array()) continue;
            for (size_t i = 0; i < list->size(); ++i) {
                const nlohmann::json& item = (*list)[i];
                if (!item.is_object() || !item.contains("uri") || !item["uri"].is_string()) continue;
                const std::string uri = item["uri"].get<std::string>();
                if (std::string problem = uri_problem(uri); !problem.empty())
                    fail(std::string(kind).substr(0, std::strlen(kind) - 1) + " " + std::to_string(i) + " URI " +
                         in_quotes(uri.size() > 200 ? uri.substr(0, 200) + "..." : uri) + " " + problem);
            }
        }
    }

    // glTF 2.x only (asset.version "2.x"; a minVersion above 2.0 needs features dynsky lacks).
    void check_version() {
        const std::string& v = model_.asset.version;
        if (!v.empty() && v.rfind("2.", 0) != 0 && v != "2")
            fail("glTF version " + in_quotes(v) + ": only glTF 2.x is supported");
        const std::string& m = model_.asset.minVersion;
        if (!m.empty() && m != "2.0" && m != "2")
            fail("needs glTF " + in_quotes(m) + " at least (asset.minVersion): dynsky reads glTF 2.0");
        if (model_.defaultScene >= int(model_.scenes.size()))
            fail("the scene to show is " + std::to_string(model_.defaultScene) + ", but the file has " +
                 std::to_string(model_.scenes.size()) + " scene(s)");
    }

    bool uses_extension(const char* name) const {
        const auto& used = model_.extensionsUsed;
        return std::find(used.begin(), used.end(), name) != used.end();
    }

    void check_extensions() {
        for (const std::string& e : model_.extensionsRequired)
            if (!supported_extensions().count(e) && !metadata_extensions().count(e))
                fail("requires glTF extension " + in_quotes(e) + ", which dynsky does not support");
        for (const std::string& e : model_.extensionsUsed)
            if (!supported_extensions().count(e) && !metadata_extensions().count(e)) {
                warn("extension " + in_quotes(e) + " is not supported: ignored");
            }
    }

    // Removes "indices" from primitives compressed by KHR_draco_mesh_compression; true if any.
    static bool drop_draco_indices(nlohmann::json* document) {
        bool dropped = false;
        auto meshes = document->find("meshes");
        if (meshes == document->end() || !meshes->is_array()) return false;
        for (nlohmann::json& mesh : *meshes) {
            auto primitives = mesh.is_object() ? mesh.find("primitives") : mesh.end();
            if (!mesh.is_object() || primitives == mesh.end() || !primitives->is_array()) continue;
            for (nlohmann::json& p : *primitives) {
                if (!p.is_object() || !p.contains("indices")) continue;
                auto ext = p.find("extensions");
                if (ext != p.end() && ext->is_object() && ext->contains("KHR_draco_mesh_compression"))
                    p.erase("indices"), dropped = true;
            }
        }
        return dropped;
    }

    // Gives EXT_meshopt_compression's fallback buffers (no uri, no data: every view of them is
    // compressed elsewhere) a 4-byte data URI; true if any.
    // tinygltf decodes a URI's '+' as a space (HTML form encoding): "a+b.bin" was looked up as
    // "a b.bin". In a URI path '+' is itself (RFC 3986): written %2B for tinygltf; the URIs as
    // written are kept to be put back.
    struct PlusUri {
        bool image;
        size_t index;
        std::string uri;
    };
    static bool encode_literal_plus(nlohmann::json* document, std::vector<PlusUri>* originals) {
        if (!document->is_object()) return false;
        bool changed = false;
        for (const char* kind : {"buffers", "images"}) {
            auto list = document->find(kind);
            if (list == document->end() || !list->is_array()) continue;
            for (size_t i = 0; i < list->size(); ++i) {
                nlohmann::json& item = (*list)[i];
                if (!item.is_object() || !item.contains("uri") || !item["uri"].is_string()) continue;
                const std::string uri = item["uri"].get<std::string>();
                if (uri.rfind("data:", 0) == 0 || uri.find('+') == std::string::npos) continue;
                std::string encoded;
                for (char c : uri) encoded += c == '+' ? std::string("%2B") : std::string(1, c);
                item["uri"] = encoded;
                originals->push_back({std::string(kind) == "images", i, uri});
                changed = true;
            }
        }
        return changed;
    }

    static bool stand_in_meshopt_fallbacks(nlohmann::json* document) {
        bool changed = false;
        auto buffers = document->find("buffers");
        if (buffers == document->end() || !buffers->is_array()) return false;
        for (nlohmann::json& b : *buffers) {
            if (!b.is_object() || b.contains("uri")) continue;
            auto ext = b.find("extensions");
            if (ext == b.end() || !ext->is_object()) continue;
            auto m = ext->find("EXT_meshopt_compression");
            if (m == ext->end() || !m->is_object() || !m->value("fallback", false)) continue;
            b["uri"] = "data:application/octet-stream;base64,AAAAAA==";
            b["byteLength"] = 4;
            changed = true;
        }
        return changed;
    }

    // The file's bytes with its JSON replaced (a GLB keeps its binary chunk, the header's lengths
    // updated).
    static std::vector<unsigned char> with_json(const std::vector<unsigned char>& bytes, bool binary,
                                                std::string json) {
        if (!binary) return std::vector<unsigned char>(json.begin(), json.end());
        while (json.size() % 4) json.push_back(' ');
        const size_t old_json = read_u32(&bytes[12]), rest = 20 + old_json;
        std::vector<unsigned char> out(bytes.begin(), bytes.begin() + 20);
        out.insert(out.end(), json.begin(), json.end());
        if (rest < bytes.size()) out.insert(out.end(), bytes.begin() + std::ptrdiff_t(rest), bytes.end());
        auto put_u32 = [&](size_t at, size_t v) {
            for (int k = 0; k < 4; ++k) out[at + size_t(k)] = static_cast<unsigned char>((v >> (8 * k)) & 0xff);
        };
        put_u32(8, out.size());
        put_u32(12, json.size());
        return out;
    }

    // ---- Buffers and accessors ----------------------------------------------------------------

    // EXT_meshopt_compression: each compressed buffer view is decoded (meshoptimizer) into a buffer
    // of its own, which the view then points at; nothing else changes.
    void decode_meshopt_views() {
        for (size_t i = 0; i < model_.bufferViews.size(); ++i) {
            const tg::Value* ext = extension(model_.bufferViews[i].extensions, "EXT_meshopt_compression");
            if (!ext) continue;
            const std::string name = "bufferView " + std::to_string(i) + " EXT_meshopt_compression";
            auto number = [&](const char* key, bool required) -> size_t {
                const tg::Value* v = member(*ext, key);
                if (!v) {
                    if (required) fail(name + ": " + key + " is missing");
                    return 0;
                }
                const double x = v->IsNumber() ? v->GetNumberAsDouble() : -1;
                if (!(x >= 0 && x <= 9007199254740992.0 && x == std::floor(x)))
                    fail(name + ": " + key + " is not a non-negative integer");
                return size_t(x);
            };
            auto text = [&](const char* key, const char* fallback) {
                const tg::Value* v = member(*ext, key);
                return v && v->IsString() ? v->Get<std::string>() : std::string(fallback);
            };
            const size_t buffer = number("buffer", true), offset = number("byteOffset", false),
                         length = number("byteLength", true), stride = number("byteStride", true),
                         count = number("count", true);
            if (buffer >= model_.buffers.size()) fail(name + ": buffer " + std::to_string(buffer) + " does not exist");
            const std::vector<unsigned char>& data = model_.buffers[buffer].data;
            if (offset > data.size() || length > data.size() - offset)
                fail(name + ": bytes " + std::to_string(offset) + " + " + std::to_string(length) +
                     " are beyond buffer " + std::to_string(buffer) + "'s " + std::to_string(data.size()));
            tg::Buffer decoded;
            const std::string problem = decode_meshopt_buffer(text("mode", ""), text("filter", "NONE"), count, stride,
                                                              data.data() + offset, length, &decoded.data);
            if (!problem.empty()) fail(name + ": " + problem);
            tg::BufferView& view = model_.bufferViews[i];
            if (view.byteLength != decoded.data.size())
                fail(name + ": count x byteStride is " + std::to_string(decoded.data.size()) +
                     " bytes but the view holds " + std::to_string(view.byteLength));
            decoded.uri = "(decoded " + name + ")";
            view.buffer = int(model_.buffers.size()), view.byteOffset = 0;
            model_.buffers.push_back(std::move(decoded));
        }
    }

    // ---- Animations -------------------------------------------------------------------------

    // Which animations play: every one, or the one `animation_` names (its name, else its index).
    // A file exported with several actions (Idle, Walk, Run) played all at once is none of them.
    void choose_animations() {
        const size_t count = model_.animations.size();
        playing_.assign(count, animation_.empty());
        auto list = [&]() {
            std::string s;
            for (size_t i = 0; i < count; ++i)
                s += (i ? ", " : "") + std::to_string(i) +
                     (model_.animations[i].name.empty() ? "" : " '" + model_.animations[i].name + "'");
            return count ? s : std::string("none");
        };
        if (animation_.empty()) {
            if (count > 1 && animation_time_ >= 0)
                warn(std::to_string(count) + " animations play together (" + list() +
                     "); --animation NAME or INDEX plays one");
            return;
        }
        // By name, else by index. Names need not be unique in glTF: the first of that name plays
        // (two named 'Walk' played together, without a word).
        std::vector<size_t> named;
        for (size_t i = 0; i < count; ++i)
            if (model_.animations[i].name == animation_) named.push_back(i);
        const bool digits = std::all_of(animation_.begin(), animation_.end(),
                                        [](char c) { return c >= '0' && c <= '9'; }) &&
                            animation_.size() < 10;
        const std::optional<size_t> index = digits && size_t(std::stoul(animation_)) < count
                                                ? std::optional<size_t>(std::stoul(animation_))
                                                : std::nullopt;
        if (!named.empty()) {
            playing_[named.front()] = true;
            if (named.size() > 1) {
                std::string others;
                for (size_t k = 1; k < named.size(); ++k) others += (k > 1 ? ", " : "") + std::to_string(named[k]);
                warn(std::to_string(named.size()) + " animations are named '" + animation_ + "': animation " +
                     std::to_string(named.front()) + " plays, not " + others + " (--animation INDEX chooses one)");
            }
            if (index && *index != named.front())
                warn("--animation " + animation_ + " is the name of animation " + std::to_string(named.front()) +
                     ", which plays (a name goes before an index), not animation " + std::to_string(*index));
        } else if (index) {
            playing_[*index] = true;
        }
        if (std::count(playing_.begin(), playing_.end(), true) == 0)
            fail("has no animation '" + animation_ + "' (--animation; its animations: " + list() + ")");
    }

    // Samples every channel of every playing animation at time t (held at the ends) into the
    // targeted nodes' translation, rotation, scale and morph weights, which the node traversal then
    // uses.
    void pose_animations(double t) {
        for (size_t ai = 0; ai < model_.animations.size(); ++ai) {
            if (ai < playing_.size() && !playing_[ai]) continue;
            const tg::Animation& a = model_.animations[ai];
            for (size_t ci = 0; ci < a.channels.size(); ++ci) {
                const tg::AnimationChannel& ch = a.channels[ci];
                const std::string what = "animation " + std::to_string(ai) + " channel " + std::to_string(ci);
                if (ch.target_node < 0) continue;  // no target node: an extension's target, ignored
                if (size_t(ch.target_node) >= model_.nodes.size())
                    fail(what + " targets node " + std::to_string(ch.target_node) + ", which does not exist");
                if (ch.sampler < 0 || size_t(ch.sampler) >= a.samplers.size())
                    fail(what + " uses sampler " + std::to_string(ch.sampler) + ", which does not exist");
                const tg::AnimationSampler& s = a.samplers[size_t(ch.sampler)];
                tg::Node& node = model_.nodes[size_t(ch.target_node)];
                const bool weights = ch.target_path == "weights";
                int width = ch.target_path == "translation" || ch.target_path == "scale" ? 3
                            : ch.target_path == "rotation"                               ? 4
                                                                                         : 0;
                if (weights) {
                    if (node.mesh >= 0 && size_t(node.mesh) < model_.meshes.size())
                        for (const tg::Primitive& p : model_.meshes[size_t(node.mesh)].primitives)
                            width = std::max(width, int(p.targets.size()));
                    if (width == 0) {
                        warn(what + ": animates the morph weights of node " + std::to_string(ch.target_node) +
                             (node.mesh < 0 ? ", which has no mesh" : ", whose mesh has no morph targets") +
                             ": nothing to move, ignored");
                        continue;
                    }
                } else if (width == 0) {
                    warn(what + ": path " + in_quotes(ch.target_path) + " is not animated (not a transform)");
                    continue;
                }
                if (!weights && node.matrix.size() == 16) {
                    warn(what + ": node " + std::to_string(ch.target_node) +
                         " has a matrix, which glTF forbids animating: the animation is not applied");
                    continue;
                }
                const std::vector<double> v = sample_channel(s, t, width, ch.target_path == "rotation", what);
                if (ch.target_path == "translation") node.translation = v;
                else if (ch.target_path == "scale") node.scale = v;
                else if (ch.target_path == "rotation") node.rotation = v;
                else node.weights = v;
            }
        }
    }

    // One sampler's value (`width` numbers) at time t.
    std::vector<double> sample_channel(const tg::AnimationSampler& s, double t, int width, bool rotation,
                                       const std::string& what) {
        const FloatArray times = read_floats(s.input, what + " input", {TINYGLTF_TYPE_SCALAR});
        const FloatArray out = read_floats(s.output, what + " output",
                                           {TINYGLTF_TYPE_SCALAR, TINYGLTF_TYPE_VEC3, TINYGLTF_TYPE_VEC4});
        const std::string mode = s.interpolation.empty() ? "LINEAR" : s.interpolation;
        const bool cubic = mode == "CUBICSPLINE";
        if (mode != "LINEAR" && mode != "STEP" && !cubic)
            fail(what + ": interpolation " + in_quotes(mode) + " is not LINEAR, STEP or CUBICSPLINE");
        const size_t keys = times.count, per_key = size_t(width) * (cubic ? 3 : 1);
        if (keys == 0) fail(what + ": the sampler has no keyframes");
        if (out.values.size() != keys * per_key)
            fail(what + ": " + std::to_string(out.values.size()) + " output numbers for " + std::to_string(keys) +
                 " keyframes of " + std::to_string(per_key));
        for (size_t k = 0; k < keys; ++k)
            if (!std::isfinite(times.values[k]) || (k > 0 && times.values[k] < times.values[k - 1]))
                fail(what + ": keyframe times must be finite and increasing (key " + std::to_string(k) + ")");
        for (float x : out.values)
            if (!std::isfinite(x)) fail(what + ": an output value is not finite");
        // The value (offset 1 of 3 for cubic splines) of key k.
        auto value = [&](size_t k, int c) {
            return double(out.values[k * per_key + (cubic ? size_t(width) : 0) + size_t(c)]);
        };
        std::vector<double> v(static_cast<size_t>(width));
        const std::vector<float>& tk = times.values;
        if (t <= tk.front() || keys == 1 || t >= tk.back()) {
            const size_t k = t <= tk.front() ? 0 : keys - 1;
            for (int c = 0; c < width; ++c) v[size_t(c)] = value(k, c);
        } else {
            // At most the last but one: a time a rounding under the last key (1/3 s against the float
            // 0.33333334) found the last key and read past the samples.
            const size_t k = std::min(size_t(std::upper_bound(tk.begin(), tk.end(), float(t)) - tk.begin()) - 1,
                                      keys - 2);
            const double d = double(tk[k + 1]) - tk[k], u = d > 0 ? std::clamp((t - tk[k]) / d, 0.0, 1.0) : 0;
            if (mode == "STEP") {
                for (int c = 0; c < width; ++c) v[size_t(c)] = value(k, c);
            } else if (cubic) {
                // Hermite: the out-tangent of k (offset 2) and the in-tangent of k + 1 (offset 0), times d.
                const double u2 = u * u, u3 = u2 * u;
                for (int c = 0; c < width; ++c) {
                    const double b = out.values[k * per_key + 2 * size_t(width) + size_t(c)];
                    const double a = out.values[(k + 1) * per_key + size_t(c)];
                    v[size_t(c)] = (2 * u3 - 3 * u2 + 1) * value(k, c) + (u3 - 2 * u2 + u) * d * b +
                                   (-2 * u3 + 3 * u2) * value(k + 1, c) + (u3 - u2) * d * a;
                }
            } else if (rotation) {  // LINEAR rotations: slerp (glTF quaternions are x, y, z, w)
                const Eigen::Quaterniond q0(value(k, 3), value(k, 0), value(k, 1), value(k, 2));
                const Eigen::Quaterniond q1(value(k + 1, 3), value(k + 1, 0), value(k + 1, 1), value(k + 1, 2));
                const Eigen::Quaterniond q = q0.normalized().slerp(u, q1.normalized());
                v = {q.x(), q.y(), q.z(), q.w()};
            } else {
                for (int c = 0; c < width; ++c) v[size_t(c)] = (1 - u) * value(k, c) + u * value(k + 1, c);
            }
        }
        if (rotation) {
            const double n = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2] + v[3] * v[3]);
            if (!(n > 1e-12)) fail(what + ": the rotation at " + number_text(t) + " s is zero");
            for (double& x : v) x /= n;
        }
        return v;
    }

    // KHR_draco_mesh_compression: each compressed primitive is decoded (Google's draco library) into
    // a buffer of its own, float attributes and 32-bit indices, and the primitive points at new
    // accessors over it; the rest of the loader then reads it as any other primitive.
    void decode_draco_primitives() {
        for (size_t mi = 0; mi < model_.meshes.size(); ++mi)
            for (size_t pi = 0; pi < model_.meshes[mi].primitives.size(); ++pi) {
                tg::Primitive& p = model_.meshes[mi].primitives[pi];
                const tg::Value* ext = extension(p.extensions, "KHR_draco_mesh_compression");
                if (ext) decode_draco(p, *ext, "mesh " + std::to_string(mi) + " primitive " + std::to_string(pi));
            }
    }

    void decode_draco(tg::Primitive& p, const tg::Value& ext, const std::string& what) {
        const std::string name = what + " KHR_draco_mesh_compression";
        const tg::Value* view = member(ext, "bufferView");
        const tg::Value* attributes = member(ext, "attributes");
        if (!view || !view->IsNumber()) fail(name + ": bufferView is missing or not a number");
        if (view->GetNumberAsInt() < 0 || size_t(view->GetNumberAsInt()) >= model_.bufferViews.size())
            fail(name + ": bufferView " + std::to_string(view->GetNumberAsInt()) + " does not exist (the file has " +
                 std::to_string(model_.bufferViews.size()) + ")");
        if (!attributes || !attributes->IsObject()) fail(name + ": attributes is missing or not an object");
        const tg::BufferView& bv = model_.bufferViews[size_t(view->GetNumberAsInt())];
        const std::vector<unsigned char>& bytes = model_.buffers[size_t(bv.buffer)].data;  // bounds validated
        std::unique_ptr<DracoMesh> mesh;
        try {
            mesh = std::make_unique<DracoMesh>(bytes.data() + bv.byteOffset, bv.byteLength);
        } catch (const Error& e) {
            fail(name + ": the compressed mesh does not decode (" + e.what() + ")");
        }
        const size_t points = mesh->points();

        tg::Buffer out;
        auto add_view = [&](const void* data, size_t size) {
            while (out.data.size() % 4) out.data.push_back(0);
            tg::BufferView v;
            v.buffer = int(model_.buffers.size());
            v.byteOffset = out.data.size();
            v.byteLength = size;
            const auto* b = static_cast<const unsigned char*>(data);
            out.data.insert(out.data.end(), b, b + size);
            model_.bufferViews.push_back(v);
            return int(model_.bufferViews.size()) - 1;
        };
        auto add_accessor = [&](int view_index, int component_type, size_t count, int type) {
            tg::Accessor a;
            a.bufferView = view_index, a.byteOffset = 0, a.componentType = component_type;
            a.count = count, a.type = type, a.normalized = false;
            model_.accessors.push_back(a);
            return int(model_.accessors.size()) - 1;
        };
        const std::vector<uint32_t> indices = mesh->indices();
        p.indices = add_accessor(add_view(indices.data(), indices.size() * 4), TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT,
                                 indices.size(), TINYGLTF_TYPE_SCALAR);
        if (p.mode < 0) p.mode = TINYGLTF_MODE_TRIANGLES;
        for (const std::string& key : attributes->Keys()) {
            const tg::Value& id_value = attributes->Get(key);
            const int id = id_value.IsNumber() ? id_value.GetNumberAsInt() : -1;
            if (id < 0 || mesh->components(uint32_t(id)) == 0)
                fail(name + ": attribute " + in_quotes(key) + " is not in the compressed mesh");
            auto it = p.attributes.find(key);
            const int components = it != p.attributes.end() && size_t(it->second) < model_.accessors.size()
                                       ? tg::GetNumComponentsInType(uint32_t(model_.accessors[size_t(it->second)].type))
                                       : mesh->components(uint32_t(id));
            std::vector<float> values;
            if (!mesh->attribute(uint32_t(id), components, &values))
                fail(name + ": attribute " + in_quotes(key) + " does not convert to " + std::to_string(components) +
                     " numbers a vertex");
            const int type = components == 1   ? TINYGLTF_TYPE_SCALAR
                             : components == 2 ? TINYGLTF_TYPE_VEC2
                             : components == 3 ? TINYGLTF_TYPE_VEC3
                                               : TINYGLTF_TYPE_VEC4;
            p.attributes[key] = add_accessor(add_view(values.data(), values.size() * 4), TINYGLTF_COMPONENT_TYPE_FLOAT,
                                             points, type);
        }
        out.uri = "(decoded " + name + ")";
        model_.buffers.push_back(std::move(out));
    }

    void validate_buffer_views() {
        for (size_t i = 0; i < model_.bufferViews.size(); ++i) {
            const tg::BufferView& v = model_.bufferViews[i];
            if (v.buffer < 0 || size_t(v.buffer) >= model_.buffers.size())
                fail("bufferView " + std::to_string(i) + " refers to buffer " + std::to_string(v.buffer) +
                     ", which does not exist");
            size_t size = model_.buffers[size_t(v.buffer)].data.size();
            if (v.byteOffset > size || v.byteLength > size - v.byteOffset)
                fail("bufferView " + std::to_string(i) + " (bytes " + std::to_string(v.byteOffset) + " + " +
                     std::to_string(v.byteLength) + ") is out of range of buffer " + std::to_string(v.buffer) + " (" +
                     std::to_string(size) + " bytes)");
        }
    }

    // Pointer to `count` elements of `element_size` bytes, `stride` apart, starting `offset` bytes
    // into bufferView `view`; fails if any byte lies outside the view.
    const unsigned char* view_span(int view, size_t offset, size_t count, size_t stride, size_t element_size,
                                   const std::string& what) const {
        if (view < 0 || size_t(view) >= model_.bufferViews.size())
            fail(what + " refers to bufferView " + std::to_string(view) + ", which does not exist");
        const tg::BufferView& v = model_.bufferViews[size_t(view)];
        const unsigned char* base = model_.buffers[size_t(v.buffer)].data.data() + v.byteOffset;
        if (count == 0) return base;
        bool fits = offset <= v.byteLength && element_size <= v.byteLength - offset &&
                    (stride == 0 || (count - 1) <= (v.byteLength - offset - element_size) / stride);
        if (!fits)
            fail(what + " is out of range: " + std::to_string(count) + " elements of " + std::to_string(element_size) +
                 " bytes (stride " + std::to_string(stride) + ") from byte " + std::to_string(offset) +
                 " do not fit bufferView " + std::to_string(view) + " (" + std::to_string(v.byteLength) + " bytes)");
        return base + offset;
    }

    const tg::Accessor& accessor(int index, const std::string& what) const {
        if (index < 0 || size_t(index) >= model_.accessors.size())
            fail(what + " refers to accessor " + std::to_string(index) + ", which does not exist");
        return model_.accessors[size_t(index)];
    }

    // Reads an accessor (dense data, then sparse substitutions) as Out (float, or uint32_t for
    // indices). `allowed_types` lists the acceptable TINYGLTF_TYPE_* values.
    template <typename Out>
    std::vector<Out> read_accessor(int index, const std::string& what_in, std::initializer_list<int> allowed_types,
                                   int* components_out = nullptr) const {
        const tg::Accessor& a = accessor(index, what_in);
        std::string what = "accessor " + std::to_string(index) + " (" + what_in + ")";
        if (std::find(allowed_types.begin(), allowed_types.end(), a.type) == allowed_types.end()) {
            std::vector<std::string> names;
            for (int t : allowed_types) names.push_back(type_name(t));
            fail(what + " has type " + type_name(a.type) + ", expected " + join(names, " or "));
        }
        size_t csize = component_size(a.componentType);
        if (csize == 0) fail(what + " has invalid componentType " + std::to_string(a.componentType));
        if (std::is_same_v<Out, uint32_t> && !(a.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
                                               a.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT ||
                                               a.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT))
            fail(what + " must have an unsigned integer componentType, not " + std::to_string(a.componentType));
        int ncomp = component_count(a.type);
        if (components_out) *components_out = ncomp;
        size_t element_size = csize * size_t(ncomp);
        size_t count = a.count;
        // An accessor without a bufferView is all zeros (but for its sparse values): bound it by the
        // data the file holds so a hostile count cannot exhaust memory (data read from a bufferView
        // is bounded by the view, checked before allocation below).
        if (a.bufferView < 0) {
            size_t buffer_bytes = 0;
            for (const tg::Buffer& b : model_.buffers) buffer_bytes += b.data.size();
            if (count > buffer_bytes + kZeroAccessorSlack)
                fail(what + " has count " + std::to_string(count) + " without a bufferView: more elements than the " +
                     std::to_string(buffer_bytes) + " bytes of buffers (plus 2^20) dynsky allows");
        }

        std::vector<Out> out;
        if (a.bufferView >= 0) {
            if (size_t(a.bufferView) >= model_.bufferViews.size())
                fail(what + " refers to bufferView " + std::to_string(a.bufferView) + ", which does not exist");
            size_t stride = model_.bufferViews[size_t(a.bufferView)].byteStride;
            if (stride == 0) stride = element_size;
            if (stride < element_size)
                fail(what + ": byteStride " + std::to_string(stride) + " is smaller than the element (" +
                     std::to_string(element_size) + " bytes)");
            const unsigned char* src = view_span(a.bufferView, a.byteOffset, count, stride, element_size, what);
            out.resize(count * size_t(ncomp));
            copy_components<Out>(a.componentType, src, stride, count, ncomp, a.normalized, out.data());
        } else {
            out.assign(count * size_t(ncomp), Out(0));
        }

        if (a.sparse.isSparse) {
            const auto& sp = a.sparse;
            if (sp.count <= 0 || size_t(sp.count) > count)
                fail(what + ": sparse count " + std::to_string(sp.count) + " is not in 1.." + std::to_string(count));
            if (sp.indices.byteOffset < 0 || sp.values.byteOffset < 0) fail(what + ": negative sparse byteOffset");
            int ict = sp.indices.componentType;
            if (!(ict == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE || ict == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT ||
                  ict == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT))
                fail(what + ": sparse indices must be unsigned integers");
            size_t n = size_t(sp.count), isize = component_size(ict);
            std::vector<uint32_t> sparse_indices(n);
            copy_components<uint32_t>(ict,
                                      view_span(sp.indices.bufferView, size_t(sp.indices.byteOffset), n, isize, isize,
                                                what + " sparse indices"),
                                      isize, n, 1, false, sparse_indices.data());
            std::vector<Out> values(n * size_t(ncomp));
            copy_components<Out>(a.componentType,
                                 view_span(sp.values.bufferView, size_t(sp.values.byteOffset), n, element_size,
                                           element_size, what + " sparse values"),
                                 element_size, n, ncomp, a.normalized, values.data());
            for (size_t k = 0; k < n; ++k) {
                size_t target = sparse_indices[k];
                if (target >= count)
                    fail(what + ": sparse index " + std::to_string(target) + " is out of range (count " +
                         std::to_string(count) + ")");
                std::copy_n(&values[k * size_t(ncomp)], ncomp, &out[target * size_t(ncomp)]);
            }
        }
        return out;
    }

    FloatArray read_floats(int index, const std::string& what, std::initializer_list<int> allowed_types) const {
        FloatArray f;
        f.values = read_accessor<float>(index, what, allowed_types, &f.components);
        f.count = f.components ? f.values.size() / size_t(f.components) : 0;
        return f;
    }

    // ---- Materials and textures -------------------------------------------------------------

    struct TextureRequest {
        int image, sampler;
        bool srgb;
        bool operator<(const TextureRequest& o) const {
            return std::tie(image, sampler, srgb) < std::tie(o.image, o.sampler, o.srgb);
        }
    };

    // Fills a slot from a glTF textureInfo (any of its three flavours).
    void read_slot(int texture, int texcoord, const tg::ExtensionMap& extensions, bool srgb, float scale,
                   TextureSlot* slot, const std::string& what) {
        if (texture < 0) return;
        if (size_t(texture) >= model_.textures.size())
            fail(what + " refers to texture " + std::to_string(texture) + ", which does not exist");
        const tg::Texture& t = model_.textures[size_t(texture)];
        int source = t.source;
        // EXT_texture_webp: its WebP image is preferred; the core source, when given, is the fallback
        // for viewers without WebP.
        if (const tg::Value* webp = extension(t.extensions, "EXT_texture_webp")) {
            const tg::Value* src = member(*webp, "source");
            if (!src || !src->IsNumber() || src->GetNumberAsInt() < 0 ||
                size_t(src->GetNumberAsInt()) >= model_.images.size())
                fail("texture " + std::to_string(texture) + ": EXT_texture_webp's source " +
                     (src && src->IsNumber()
                          ? std::to_string(src->GetNumberAsInt()) + " does not exist (the file has " +
                                std::to_string(model_.images.size()) + " images)"
                          : std::string("is missing or not an image index")));
            source = src->GetNumberAsInt();
        }
        if (source < 0) {
            warn(what + ": texture " + std::to_string(texture) + " has no core image source (an image-format " +
                 "extension?): slot ignored");
            return;
        }
        if (size_t(source) >= model_.images.size())
            fail("texture " + std::to_string(texture) + " refers to image " + std::to_string(source) +
                 ", which does not exist");
        if (t.sampler >= 0 && size_t(t.sampler) >= model_.samplers.size())
            fail("texture " + std::to_string(texture) + " refers to sampler " + std::to_string(t.sampler) +
                 ", which does not exist");
        slot->texcoord = texcoord;
        slot->scale = scale;
        if (const tg::Value* tt = extension(extensions, "KHR_texture_transform")) {
            Vec2 offset = vec2_or(member(*tt, "offset"), Vec2(0, 0));
            Vec2 sc = vec2_or(member(*tt, "scale"), Vec2(1, 1));
            float rotation = float(number_or(member(*tt, "rotation"), 0.0));
            slot->uv_transform = texture_transform_matrix(offset, rotation, sc);
            if (!slot->uv_transform.allFinite())
                fail(what +
                     ": KHR_texture_transform is not finite (offset, scale or rotation beyond single precision)");
            if (const tg::Value* tc = member(*tt, "texCoord"); tc && tc->IsNumber())
                slot->texcoord = tc->GetNumberAsInt();
        }
        if (slot->texcoord < 0 || slot->texcoord > 1) {
            warn(what + " uses TEXCOORD_" + std::to_string(slot->texcoord) +
                 ": only TEXCOORD_0 and TEXCOORD_1 are read, using 0");
            slot->texcoord = 0;
        }
        TextureRequest key{source, t.sampler, srgb};
        auto it = texture_of_request_.find(key);
        if (it == texture_of_request_.end()) {
            it = texture_of_request_.emplace(key, int(requests_.size())).first;
            requests_.push_back(key);
        }
        slot->texture = it->second;
    }

    void build_materials() {
        for (size_t i = 0; i < model_.materials.size(); ++i) {
            const tg::Material& m = model_.materials[i];
            Material out;
            out.name = m.name.empty() ? "material " + std::to_string(i) : m.name;
            std::string what = m.name.empty() ? out.name : "material " + in_quotes(out.name);
            const tg::PbrMetallicRoughness& pbr = m.pbrMetallicRoughness;
            if (pbr.baseColorFactor.size() != 4)
                fail(what + ": baseColorFactor has " + std::to_string(pbr.baseColorFactor.size()) +
                     " numbers, not 4 (RGBA)");
            out.base_color = Color(float(pbr.baseColorFactor[0]), float(pbr.baseColorFactor[1]),
                                   float(pbr.baseColorFactor[2]));
            out.base_alpha = float(pbr.baseColorFactor[3]);
            for (auto [name, value] : {std::pair<const char*, double>{"metallicFactor", pbr.metallicFactor},
                                       std::pair<const char*, double>{"roughnessFactor", pbr.roughnessFactor}})
                if (!(value >= -1e-4 && value <= 1 + 1e-4))
                    warn(what + ": " + name + " " + number_text(value) + " is outside [0, 1], clamped");
            out.metallic = clamp(float(pbr.metallicFactor), 0.0f, 1.0f);
            out.roughness = clamp(float(pbr.roughnessFactor), 0.0f, 1.0f);
            read_slot(pbr.baseColorTexture.index, pbr.baseColorTexture.texCoord, pbr.baseColorTexture.extensions, true,
                      1.0f, &out.base_color_texture, what + " baseColorTexture");
            read_slot(pbr.metallicRoughnessTexture.index, pbr.metallicRoughnessTexture.texCoord,
                      pbr.metallicRoughnessTexture.extensions, false, 1.0f, &out.metallic_roughness_texture,
                      what + " metallicRoughnessTexture");
            read_slot(m.normalTexture.index, m.normalTexture.texCoord, m.normalTexture.extensions, false,
                      float(m.normalTexture.scale), &out.normal_texture, what + " normalTexture");
            read_slot(m.occlusionTexture.index, m.occlusionTexture.texCoord, m.occlusionTexture.extensions, false,
                      float(m.occlusionTexture.strength), &out.occlusion_texture, what + " occlusionTexture");
            read_slot(m.emissiveTexture.index, m.emissiveTexture.texCoord, m.emissiveTexture.extensions, true, 1.0f,
                      &out.emissive_texture, what + " emissiveTexture");
            if (m.emissiveFactor.size() == 3)
                out.emissive = Color(float(m.emissiveFactor[0]), float(m.emissiveFactor[1]),
                                     float(m.emissiveFactor[2]));
            out.unlit = extension(m.extensions, "KHR_materials_unlit") != nullptr;
            double strength = 1.0;
            if (const tg::Value* es = extension(m.extensions, "KHR_materials_emissive_strength"))
                strength = number_or(member(*es, "emissiveStrength"), 1.0);
            // The spec's ranges: factors in [0, 1], strength >= 0. Negative, non-finite or absurd
            // values mean a broken file (1e39 overflowed to an infinite emission that rendered
            // black); an emissive factor above 1 is common (exporters before the strength
            // extension) and kept, a base colour above 1 (more light out than in) is clamped.
            for (int c = 0; c < 3; ++c) {
                const double e = m.emissiveFactor.size() == 3 ? m.emissiveFactor[size_t(c)] : 0.0;
                if (!(e >= -1e-4 && e <= kMaxEmissiveStrength))
                    fail(what + ": emissiveFactor " + number_text(e) + " is " +
                         (e < 0 ? std::string("negative (the spec's range is [0, 1])")
                                : "not a number or above " + number_text(kMaxEmissiveStrength) +
                                      " (the spec's range is [0, 1]; brighter emission belongs in "
                                      "KHR_materials_emissive_strength)"));
            }
            if (!(strength >= 0 && strength <= kMaxEmissiveStrength))
                fail(what + ": KHR_materials_emissive_strength " + number_text(strength) + " is outside [0, " +
                     number_text(kMaxEmissiveStrength) + "]");
            const double emission = (out.emissive.max(0.0f) * float(strength)).maxCoeff();
            if (emission > kMaxEmissiveStrength)
                fail(what + ": emission " + number_text(emission) + " (emissiveFactor x strength) is above " +
                     number_text(kMaxEmissiveStrength));
            for (size_t c = 0; c < pbr.baseColorFactor.size(); ++c) {
                const double b = pbr.baseColorFactor[c];
                if (!(b >= -1e-4 && b <= kMaxEmissiveStrength))
                    fail(what + ": baseColorFactor " + number_text(b) + " is " +
                         (b < 0 ? std::string("negative")
                                : "not a number or above " + number_text(kMaxEmissiveStrength)) +
                         " (the spec's range is [0, 1])");
                if (b > 1 + 1e-4 && c < 3) warn(what + ": baseColorFactor " + number_text(b) + " above 1, taken as 1");
            }
            out.emissive = out.emissive.max(0.0f) * float(strength);
            out.base_color = out.base_color.max(0.0f).min(1.0f);
            out.base_alpha = std::clamp(out.base_alpha, 0.0f, 1.0f);
            if (const tg::Value* sg = extension(m.extensions, "KHR_materials_pbrSpecularGlossiness"))
                read_specular_glossiness(*sg, &out, what);
            if (const tg::Value* sp = extension(m.extensions, "KHR_materials_specular")) read_specular(*sp, &out, what);
            if (const tg::Value* tr = extension(m.extensions, "KHR_materials_transmission"))
                read_transmission(*tr, &out, what);
            if (const tg::Value* cc = extension(m.extensions, "KHR_materials_clearcoat"))
                read_clearcoat(*cc, &out, what);
            if (const tg::Value* ior = extension(m.extensions, "KHR_materials_ior")) read_ior(*ior, &out, what);
            if (const tg::Value* sheen = extension(m.extensions, "KHR_materials_sheen")) read_sheen(*sheen, &out, what);
            if (const tg::Value* an = extension(m.extensions, "KHR_materials_anisotropy"))
                read_anisotropy(*an, &out, what);
            if (const tg::Value* volume = extension(m.extensions, "KHR_materials_volume"))
                read_volume(*volume, &out, what);
            if (m.alphaMode == "MASK") out.alpha_mode = AlphaMode::Mask;
            else if (m.alphaMode == "BLEND") out.alpha_mode = AlphaMode::Blend;
            else if (m.alphaMode != "OPAQUE" && !m.alphaMode.empty())
                warn(what + ": unknown alphaMode " + in_quotes(m.alphaMode) + ", treated as OPAQUE");
            out.alpha_cutoff = float(m.alphaCutoff);
            out.double_sided = m.doubleSided;
            scene_.materials.push_back(std::move(out));
        }
    }

    // A factor of an extension in [0, 1] (absent: `fallback`), refused naming it otherwise.
    double extension_factor(const tg::Value& ext, const char* key, double fallback, const std::string& what,
                            const char* extension_name) {
        const tg::Value* v = member(ext, key);
        if (!v) return fallback;
        const double x = v->IsNumber() ? v->GetNumberAsDouble() : std::nan("");
        if (!v->IsNumber()) fail(what + ": " + extension_name + " " + key + " is not a number");
        if (!(x >= 0 && x <= 1))
            fail(what + ": " + extension_name + " " + key + " " + number_text(x) + " is outside [0, 1]");
        return x;
    }

    // An extension's array of n numbers in [0, upper] (present: the caller checked), refused naming it.
    std::vector<float> extension_numbers(const tg::Value& array, int n, const char* key, const std::string& what,
                                         const char* extension_name, double upper) {
        if (!array.IsArray() || int(array.ArrayLen()) != n)
            fail(what + ": " + extension_name + " " + key + " is not " + std::to_string(n) + " numbers");
        std::vector<float> values(static_cast<size_t>(n));
        for (int k = 0; k < n; ++k) {
            const tg::Value& e = array.Get(k);
            const double v = e.IsNumber() ? e.GetNumberAsDouble() : std::nan("");
            if (!(v >= 0 && v <= upper))
                fail(what + ": " + extension_name + " " + key + " " +
                     (e.IsNumber() ? number_text(v) : std::string("holds a non-number")) + " is outside [0, " +
                     number_text(upper) + "]");
            values[size_t(k)] = float(v);
        }
        return values;
    }

    // An extension's RGB factor: 3 numbers in [0, upper], or `fallback` when absent.
    Color extension_colour(const tg::Value& ext, const char* key, const Color& fallback, const std::string& what,
                           const char* extension_name, double upper = 1) {
        const tg::Value* c = member(ext, key);
        if (!c) return fallback;
        const std::vector<float> v = extension_numbers(*c, 3, key, what, extension_name, upper);
        return Color(v[0], v[1], v[2]);
    }

    // A textureInfo object inside an extension ({"index", "texCoord", "extensions"}) into a slot.
    void read_extension_slot(const tg::Value& ext, const char* key, TextureSlot* slot, const std::string& what,
                             bool srgb = false) {
        const tg::Value* info = member(ext, key);
        if (!info || !info->IsObject()) return;
        const tg::Value* index = member(*info, "index");
        if (!index || !index->IsNumber()) fail(what + ": " + key + " has no texture index");
        if (index->GetNumberAsInt() < 0)
            fail(what + " " + key + " refers to texture " + std::to_string(index->GetNumberAsInt()) +
                 ", which does not exist");
        tg::ExtensionMap extensions;
        if (const tg::Value* e = member(*info, "extensions"); e && e->IsObject())
            for (const std::string& k : e->Keys()) extensions[k] = e->Get(k);
        const tg::Value* texcoord = member(*info, "texCoord");
        read_slot(index->GetNumberAsInt(), texcoord && texcoord->IsNumber() ? texcoord->GetNumberAsInt() : 0,
                  extensions, srgb, 1.0f, slot, what + " " + key);
    }

    // KHR_materials_specular: specularFactor in [0, 1] (scales the dielectric's Fresnel, F90
    // included) and its texture's A; specularColorFactor (F0 tint, finite and not negative: above 1
    // raises F0, capped at 1) and its texture's RGB (sRGB).
    void read_specular(const tg::Value& ext, Material* out, const std::string& what) {
        const char* name = "KHR_materials_specular";
        out->specular = float(extension_factor(ext, "specularFactor", 1.0, what, name));
        read_extension_slot(ext, "specularTexture", &out->specular_texture, what);
        out->specular_color = extension_colour(ext, "specularColorFactor", Color::Ones(), what, name, 1e6);
        read_extension_slot(ext, "specularColorTexture", &out->specular_color_texture, what, true);
    }

    // KHR_materials_pbrSpecularGlossiness (archived by Khronos, common in files exported before
    // 2020): replaces pbrMetallicRoughness (the fallback for clients without it). Mapped onto the
    // metal-rough model as gltf-transform's conversion does: a dielectric (metallic 0) whose base is
    // the diffuse colour (diffuseFactor RGBA, diffuseTexture sRGB RGBA), whose F0 is the specular
    // colour (specularFactor, times the specularGlossinessTexture's sRGB RGB: the specular colour of
    // KHR_materials_specular scaled by 1 / 0.04, the F0 of IOR 1.5) and whose roughness is
    // 1 - glossiness (glossinessFactor times the texture's linear A).
    void read_specular_glossiness(const tg::Value& ext, Material* out, const std::string& what) {
        const char* name = "KHR_materials_pbrSpecularGlossiness";
        out->base_color = Color::Ones(), out->base_alpha = 1.0f;
        if (const tg::Value* d = member(ext, "diffuseFactor")) {
            const std::vector<float> rgba = extension_numbers(*d, 4, "diffuseFactor", what, name, 1);
            out->base_color = Color(rgba[0], rgba[1], rgba[2]), out->base_alpha = rgba[3];
        }
        out->base_color_texture = TextureSlot();
        read_extension_slot(ext, "diffuseTexture", &out->base_color_texture, what, true);
        out->metallic = 0;
        out->metallic_roughness_texture = TextureSlot();
        out->glossiness = float(extension_factor(ext, "glossinessFactor", 1.0, what, name));
        out->roughness = 1 - out->glossiness;
        out->specular_color = extension_colour(ext, "specularFactor", Color::Ones(), what, name) / 0.04f;
        read_extension_slot(ext, "specularGlossinessTexture", &out->specular_color_texture, what, true);
        out->glossiness_texture = out->specular_color_texture;
    }

    // KHR_materials_anisotropy: anisotropyStrength in [0, 1], anisotropyRotation (radians, finite),
    // anisotropyTexture (linear: RG a direction, B a strength).
    void read_anisotropy(const tg::Value& ext, Material* out, const std::string& what) {
        const char* name = "KHR_materials_anisotropy";
        out->anisotropy_strength = float(extension_factor(ext, "anisotropyStrength", 0.0, what, name));
        if (const tg::Value* r = member(ext, "anisotropyRotation")) {
            if (!r->IsNumber()) fail(what + ": " + name + " anisotropyRotation is not a number");
            const double x = r->GetNumberAsDouble();
            if (!std::isfinite(x) || std::abs(x) > 1e6)
                fail(what + ": " + name + " anisotropyRotation " + number_text(x) + " is not an angle in radians");
            out->anisotropy_rotation = float(std::remainder(x, 2 * kPiD));
        }
        read_extension_slot(ext, "anisotropyTexture", &out->anisotropy_texture, what);
    }

    // KHR_materials_sheen: sheenColorFactor (3 numbers in [0, 1], default black: no sheen) and
    // sheenRoughnessFactor in [0, 1]; sheenColorTexture (sRGB RGB) and sheenRoughnessTexture (its A).
    void read_sheen(const tg::Value& ext, Material* out, const std::string& what) {
        const char* name = "KHR_materials_sheen";
        out->sheen_roughness = float(extension_factor(ext, "sheenRoughnessFactor", 0.0, what, name));
        out->sheen_color = extension_colour(ext, "sheenColorFactor", Color::Zero(), what, name);
        read_extension_slot(ext, "sheenColorTexture", &out->sheen_color_texture, what, true);
        read_extension_slot(ext, "sheenRoughnessTexture", &out->sheen_roughness_texture, what);
    }

    // KHR_materials_clearcoat: clearcoatFactor and clearcoatRoughnessFactor in [0, 1], their textures
    // (R and G). clearcoatNormalTexture is not read: the coat takes the surface's own normal.
    void read_clearcoat(const tg::Value& ext, Material* out, const std::string& what) {
        const char* name = "KHR_materials_clearcoat";
        out->clearcoat = float(extension_factor(ext, "clearcoatFactor", 0.0, what, name));
        out->clearcoat_roughness = float(extension_factor(ext, "clearcoatRoughnessFactor", 0.0, what, name));
        read_extension_slot(ext, "clearcoatTexture", &out->clearcoat_texture, what);
        read_extension_slot(ext, "clearcoatRoughnessTexture", &out->clearcoat_roughness_texture, what);
        if (out->clearcoat > 0 && member(ext, "clearcoatNormalTexture"))
            warn(what +
                 ": KHR_materials_clearcoat clearcoatNormalTexture is not read: the coat follows the "
                 "surface's own normal");
    }

    // KHR_materials_ior: 1 (no reflection at normal incidence) and above; water 1.33, glass 1.5,
    // diamond 2.42. The extension's 0 (and values below 1) fall back to glTF's 1.5, said.
    void read_ior(const tg::Value& ext, Material* out, const std::string& what) {
        const tg::Value* v = member(ext, "ior");
        if (!v) return;
        const double ior = v->IsNumber() ? v->GetNumberAsDouble() : std::nan("");
        if (!(ior >= 0 && ior <= 100))
            fail(what + ": KHR_materials_ior ior " +
                 (v->IsNumber() ? number_text(ior) : std::string("is not a number")) + " is outside [1, 100]");
        if (ior < 1) {
            warn(what + ": KHR_materials_ior ior " + number_text(ior) + " is below 1: glTF's 1.5 used");
            return;
        }
        out->ior = float(ior);
    }

    // KHR_materials_volume, rendered thin-walled (no refraction): the slab's absorption tints what
    // passes once, attenuationColor^(thicknessFactor / attenuationDistance), so a bottle of white base
    // and green attenuation is green glass rather than clear. The thickness is taken as it is (the
    // node's scale and the path's slant are not), its texture not read.
    void read_volume(const tg::Value& ext, Material* out, const std::string& what) {
        const char* name = "KHR_materials_volume";
        auto number = [&](const char* key, double fallback) {
            const tg::Value* v = member(ext, key);
            if (!v) return fallback;
            if (!v->IsNumber()) fail(what + ": " + name + " " + key + " is not a number");
            return v->GetNumberAsDouble();
        };
        const double thickness = number("thicknessFactor", 0.0);
        const double distance = number("attenuationDistance", std::numeric_limits<double>::infinity());
        if (!(thickness >= 0 && thickness <= kMaxCoordinate))
            fail(what + ": " + name + " thicknessFactor " + number_text(thickness) + " is not a thickness (>= 0)");
        if (!(distance > 0))
            fail(what + ": " + name + " attenuationDistance " + number_text(distance) + " is not positive");
        const Color colour = extension_colour(ext, "attenuationColor", Color::Ones(), what, name);
        if (out->transmission > 0 && thickness > 0 && std::isfinite(distance))
            out->volume_tint = colour.pow(float(thickness / distance));
        if (out->transmission > 0)
            warn(what + ": " + name +
                 " is rendered thin: its absorption tints what passes, without refraction through the thickness");
    }

    // KHR_materials_transmission: transmissionFactor in [0, 1] and transmissionTexture (R, linear).
    // Rendered thin-walled and sharp (bsdf.h): a rough glass is seen through as a clear one.
    void read_transmission(const tg::Value& ext, Material* out, const std::string& what) {
        out->transmission = float(extension_factor(ext, "transmissionFactor", 0.0, what, "KHR_materials_transmission"));
        read_extension_slot(ext, "transmissionTexture", &out->transmission_texture, what);
        if (out->transmission > 0 && out->roughness > 0.2f)
            warn(what + ": rough transmission (roughness " + number_text(out->roughness) +
                 ") is rendered as clear glass: what lies behind is seen sharp, not blurred");
    }

    // The encoded bytes of an image: from its file or data URI (kept by keep_encoded_image), or
    // from its bufferView.
    std::pair<const unsigned char*, size_t> encoded_image(int index) const {
        const tg::Image& img = model_.images[size_t(index)];
        if (img.bufferView >= 0) {
            if (size_t(img.bufferView) >= model_.bufferViews.size())
                fail("image " + std::to_string(index) + " refers to bufferView " + std::to_string(img.bufferView) +
                     ", which does not exist");
            size_t n = model_.bufferViews[size_t(img.bufferView)].byteLength;
            return {view_span(img.bufferView, 0, 1, 0, n, "image " + std::to_string(index)), n};
        }
        if (img.image.empty()) {
            std::string file = percent_decoded(img.uri);
            std::string dir = std::filesystem::path(path_).parent_path().string();
            if (!dir.empty()) file = (std::filesystem::path(dir) / file).string();
            std::error_code ec;
            if (std::filesystem::is_regular_file(file, ec) && std::filesystem::file_size(file, ec) == 0 && !ec)
                fail("texture file " + in_quotes(file) + " (image " + std::to_string(index) + ") is empty (0 bytes)");
            fail("missing texture file " + in_quotes(file) + " (image " + std::to_string(index) + ")");
        }
        return {img.image.data(), img.image.size()};
    }

    // Why encoded bytes did not decode, in words: stb says "Unknown image format" also for a PNG
    // that is corrupt, cut short or larger than it accepts.
    static std::string encoded_image_problem(const unsigned char* b, size_t n, const std::string& decoder) {
        if (is_png(b, n)) {
            long long w = 0, h = 0;
            if (image_header_size(b, n, &w, &h))
                if (const std::string size = image_size_problem(w, h, 4); !size.empty()) return size;
            return "a PNG that cannot be decoded (corrupt or cut short: " + decoder + ")";
        }
        if (n >= 3 && b[0] == 0xff && b[1] == 0xd8 && b[2] == 0xff)
            return "a JPEG that cannot be decoded (corrupt or cut short: " + decoder + ")";
        if (n == 0) return "empty";
        return decoder + " (glTF textures are PNG or JPEG, or WebP with EXT_texture_webp)";
    }

    static TextureWrap wrap_mode(int gl) {
        switch (gl) {
            case TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE: return TextureWrap::ClampToEdge;
            case TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT: return TextureWrap::MirroredRepeat;
            default: return TextureWrap::Repeat;
        }
    }

    void build_textures() {
        // Decode every image some slot uses, once, in parallel (stb, through tinygltf).
        std::vector<int> images;
        for (const TextureRequest& r : requests_) images.push_back(r.image);
        std::sort(images.begin(), images.end());
        images.erase(std::unique(images.begin(), images.end()), images.end());
        std::vector<std::pair<const unsigned char*, size_t>> encoded;
        for (int i : images) encoded.push_back(encoded_image(i));  // fails here for missing files

        // What decoding them all costs, from their headers, against this machine's memory: 18 PNGs of
        // 8192^2 zeros (5 MB of files) would take 20 GB and end in an out-of-memory kill, not an error.
        {
            double texels = 0, largest = 0;
            int largest_image = -1;
            for (size_t k = 0; k < images.size(); ++k) {
                long long w = 0, h = 0;
                // One beyond the per-image limits is refused with its own message when it is decoded.
                if (image_header_size(encoded[k].first, encoded[k].second, &w, &h) &&
                    image_size_problem(w, h, 4).empty()) {
                    texels += double(w) * h;
                    if (double(w) * h > largest) largest = double(w) * h, largest_image = images[k];
                }
            }
            // Decoded as float RGBA, kept as 8-bit or float RGBA: 18-21 bytes a texel measured at the peak.
            const double need = texels * 20, have = double(sysconf(_SC_PHYS_PAGES)) * double(sysconf(_SC_PAGE_SIZE));
            if (have > 0 && need > 0.9 * have)
                fail("its " + std::to_string(images.size()) + " texture image(s) hold " + number_text(texels, 3) +
                     " texels (image " + std::to_string(largest_image) + " alone " + number_text(largest, 3) +
                     "): about " + number_text(need / 1073741824.0, 3) + " GiB to decode, more than this machine's " +
                     number_text(have / 1073741824.0, 3) + " GiB of memory allows (reduce the textures)");
        }

        struct Decoded {
            int width = 0, height = 0;
            std::vector<float> rgba;
            std::string error;
        };
        std::vector<Decoded> decoded(images.size());
        tbb::parallel_for(size_t(0), images.size(), [&](size_t k) {
            // The size in the header decides the allocation: check it before stb decodes.
            long long header_w = 0, header_h = 0;
            if (image_header_size(encoded[k].first, encoded[k].second, &header_w, &header_h)) {
                std::string problem = image_size_problem(header_w, header_h, 4);
                if (!problem.empty()) {
                    // A few bytes whose first ones look like a header ("GIF89a garbage") are not a
                    // large image: say so beside the size.
                    if (encoded[k].second < 1024)
                        problem = "not an image, or a corrupt one (a file of " + std::to_string(encoded[k].second) +
                                  " bytes whose header says: " + problem + ")";
                    decoded[k].error = problem;
                    return;
                }
            }
            // PNGs through libpng (OpenCV), which checks every chunk's CRC and the zlib stream: stb
            // decoded a PNG with a changed byte into garbage texels (exit 0). Lossless either way.
            // WebP (EXT_texture_webp), which stb does not read, through OpenCV's libwebp as well.
            const bool png = is_png(encoded[k].first, encoded[k].second);
            if (png || is_webp(encoded[k].first, encoded[k].second)) {
                decoded[k].error = decode_with_opencv(encoded[k].first, encoded[k].second, png ? "PNG" : "WebP",
                                                      &decoded[k].width, &decoded[k].height, &decoded[k].rgba);
                // A grey PNG's transparent key colour: once libpng has checked the file, stb (which
                // turns the key into alpha) decodes it below.
                if (!(png && decoded[k].error.empty() &&
                      is_grey_png_with_key_colour(encoded[k].first, encoded[k].second)))
                    return;
            }
            tg::Image img;
            std::string err, warn_text;
            if (encoded[k].second > size_t(std::numeric_limits<int>::max()) ||
                !tg::LoadImageData(&img, images[k], &err, &warn_text, 0, 0, encoded[k].first, int(encoded[k].second),
                                   nullptr)) {
                decoded[k].error = encoded_image_problem(encoded[k].first, encoded[k].second,
                                                         join(split_lines(err), "; "));
                return;
            }
            size_t n = size_t(img.width) * size_t(img.height) * 4;
            if (img.component != 4 || (img.bits != 8 && img.bits != 16) ||
                img.image.size() != n * size_t(img.bits / 8)) {
                decoded[k].error = "unexpected decoded layout";
                return;
            }
            decoded[k].width = img.width, decoded[k].height = img.height;
            std::vector<float>& rgba = decoded[k].rgba;
            rgba.resize(n);
            const unsigned char* src = img.image.data();
            float* dst = rgba.data();
            if (img.bits == 8) {
                for (size_t j = 0; j < n; ++j) dst[j] = float(src[j]) * (1.0f / 255.0f);
            } else {
                for (size_t j = 0; j < n; ++j) {
                    uint16_t v;
                    std::memcpy(&v, src + 2 * j, 2);
                    dst[j] = float(v) * (1.0f / 65535.0f);
                }
            }
        });
        for (size_t k = 0; k < images.size(); ++k)
            if (!decoded[k].error.empty()) {
                const tg::Image& img = model_.images[size_t(images[k])];
                std::string name = !img.uri.empty() ? img.uri : img.name;
                // An embedded image is named by its data: URI's head, not its megabytes of base64.
                if (name.rfind("data:", 0) == 0) name = name.substr(0, std::min(name.find(','), size_t(80))) + ",...";
                fail("cannot decode image " + std::to_string(images[k]) + (name.empty() ? "" : " " + in_quotes(name)) +
                     ": " + decoded[k].error);
            }
        for (size_t i = 0; i < model_.images.size(); ++i) {
            const tg::Image& img = model_.images[i];
            if (img.bufferView < 0 && img.image.empty() && !std::binary_search(images.begin(), images.end(), int(i)))
                warn("unused image " + std::to_string(i) + " " + in_quotes(img.uri) + " is missing");
        }

        // One Texture per (image, sampler, colour space); sRGB decoding happens in the constructor.
        // Per image, the last texture made from it takes its pixels instead of copying them.
        std::vector<std::vector<size_t>> requests_of_image(images.size());
        for (size_t r = 0; r < requests_.size(); ++r)
            requests_of_image[size_t(std::lower_bound(images.begin(), images.end(), requests_[r].image) -
                                     images.begin())]
                .push_back(r);
        scene_.textures.resize(requests_.size());
        tbb::parallel_for(size_t(0), images.size(), [&](size_t k) {
            const std::vector<size_t>& users = requests_of_image[k];
            for (size_t u = 0; u < users.size(); ++u) {
                const TextureRequest& req = requests_[users[u]];
                TextureWrap ws = TextureWrap::Repeat, wt = TextureWrap::Repeat;
                TextureFilter filter = TextureFilter::Linear;
                if (req.sampler >= 0) {
                    const tg::Sampler& s = model_.samplers[size_t(req.sampler)];
                    ws = wrap_mode(s.wrapS), wt = wrap_mode(s.wrapT);
                    // No mip maps: the magnification filter decides; minFilter is ignored.
                    if (s.magFilter == TINYGLTF_TEXTURE_FILTER_NEAREST) filter = TextureFilter::Nearest;
                }
                const tg::Image& img = model_.images[size_t(req.image)];
                std::string name = !img.name.empty()  ? img.name
                                   : !img.uri.empty() ? img.uri
                                                      : "image " + std::to_string(req.image);
                std::vector<float> rgba = u + 1 == users.size() ? std::move(decoded[k].rgba) : decoded[k].rgba;
                scene_.textures[users[u]] = std::make_shared<Texture>(name, decoded[k].width, decoded[k].height,
                                                                      std::move(rgba), req.srgb, ws, wt, filter);
            }
        });
    }

    // ---- Meshes -----------------------------------------------------------------------------

    // Triangle list from a primitive's index stream, per glTF 2.0 section 3.7.2.1.
    // `indexed`: the stream is the primitive's indices, else its vertices in order (said so).
    std::vector<uint32_t> triangulate(int mode, const std::vector<uint32_t>& v, const std::string& what,
                                      bool indexed = true) {
        std::vector<uint32_t> tri;
        size_t n = v.size();
        if (mode == TINYGLTF_MODE_TRIANGLES) {
            if (n % 3)
                warn(what + ": " + std::to_string(n) + (indexed ? " indices" : " vertices (no indices)") +
                     " is not a multiple of 3, the last " + std::to_string(n % 3) + " ignored");
            tri.assign(v.begin(), v.begin() + std::ptrdiff_t(n - n % 3));
        } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
            for (size_t i = 0; i + 2 < n; ++i) {
                // Every other triangle swaps its last two vertices so all keep the strip's winding.
                bool odd = i % 2;
                tri.insert(tri.end(), {v[i], v[i + 1 + odd], v[i + 2 - odd]});
            }
        } else {  // TRIANGLE_FAN
            for (size_t i = 0; i + 2 < n; ++i) tri.insert(tri.end(), {v[i + 1], v[i + 2], v[0]});
        }
        return tri;
    }

    template <int N>
    static std::vector<Eigen::Matrix<float, N, 1>> to_vectors(const FloatArray& f) {
        std::vector<Eigen::Matrix<float, N, 1>> out(f.count);
        for (size_t i = 0; i < f.count; ++i)
            for (int c = 0; c < N; ++c) out[i][c] = f.values[i * size_t(f.components) + size_t(c)];
        return out;
    }

    // Adds the morph targets' `attribute` displacements, weighted (glTF: base + sum w_i target_i).
    void add_morph_deltas(const tg::Primitive& p, const std::vector<double>& weights, const char* attribute,
                          const std::string& what, std::vector<Vec3>* values) const {
        for (size_t t = 0; t < p.targets.size(); ++t) {
            auto it = p.targets[t].find(attribute);
            if (it == p.targets[t].end()) continue;
            const std::string name = what + " morph target " + std::to_string(t) + " " + attribute;
            // Every target's size checked, weighted or not: one whose weight an animation raised only
            // later failed at that frame, after the frames before it were written.
            if (it->second < 0 || size_t(it->second) >= model_.accessors.size())
                fail(name + " refers to accessor " + std::to_string(it->second) + ", which does not exist");
            if (model_.accessors[size_t(it->second)].count != values->size())
                fail(name + " has " + std::to_string(model_.accessors[size_t(it->second)].count) +
                     " elements but the primitive has " + std::to_string(values->size()) + " vertices");
            if (t >= weights.size() || weights[t] == 0) continue;
            FloatArray d = read_floats(it->second, name, {TINYGLTF_TYPE_VEC3});
            if (d.count != values->size())
                fail(name + " has " + std::to_string(d.count) + " elements but the primitive has " +
                     std::to_string(values->size()) + " vertices");
            const float w = float(weights[t]);
            for (size_t i = 0; i < d.count; ++i)
                (*values)[i] += w * Vec3(d.values[3 * i], d.values[3 * i + 1], d.values[3 * i + 2]);
        }
    }

    // Linear blend skinning at the pose the nodes' transforms give (animated ones as sampled): each
    // vertex moves by sum_k w_k joint[j_k] (joint = the joint's world transform x its inverse bind
    // matrix), into world space. Writes each vertex's normal matrix (the inverse transpose).
    void skin_positions(const tg::Primitive& p, const VertexPose& pose, const std::string& what, TriangleMesh* mesh,
                        std::vector<Eigen::Matrix3f>* normal_matrices) {
        const size_t n = mesh->positions.size();
        std::vector<Eigen::Matrix4d> blended(n, Eigen::Matrix4d::Zero());
        std::vector<double> total(n, 0.0);
        bool any_set = false;
        for (int set = 0; set < 4; ++set) {
            auto j = p.attributes.find("JOINTS_" + std::to_string(set));
            auto w = p.attributes.find("WEIGHTS_" + std::to_string(set));
            if (j == p.attributes.end() && w == p.attributes.end()) break;
            const std::string jn = what + " JOINTS_" + std::to_string(set),
                              wn = what + " WEIGHTS_" + std::to_string(set);
            if (j == p.attributes.end() || w == p.attributes.end())
                fail((j == p.attributes.end() ? wn + " has no JOINTS_" : jn + " has no WEIGHTS_") +
                     std::to_string(set) + " beside it (skinning needs both)");
            FloatArray joints = read_floats(j->second, jn, {TINYGLTF_TYPE_VEC4});
            FloatArray weights = read_floats(w->second, wn, {TINYGLTF_TYPE_VEC4});
            if (joints.count != n || weights.count != n)
                fail(what + ": " + jn + " and " + wn + " have " + std::to_string(joints.count) + " and " +
                     std::to_string(weights.count) + " elements but POSITION has " + std::to_string(n));
            for (size_t i = 0; i < n; ++i)
                for (int k = 0; k < 4; ++k) {
                    const double wk = weights.values[4 * i + size_t(k)];
                    if (!(wk >= 0) || !std::isfinite(wk))
                        fail(wn + " " + std::to_string(i) + " has weight " + number_text(wk) +
                             ": skin weights are finite and not negative");
                    if (wk == 0) continue;
                    const float jk = joints.values[4 * i + size_t(k)];
                    if (!(jk >= 0 && jk < float(pose.joints.size())))
                        fail(jn + " " + std::to_string(i) + " names joint " + number_text(jk) + ", but the skin has " +
                             std::to_string(pose.joints.size()) + " joints");
                    blended[i] += wk * pose.joints[size_t(jk)];
                    total[i] += wk;
                }
            any_set = true;
        }
        if (!any_set) {
            // A skinned node whose primitive has no joints: the spec leaves it to the node's own
            // transform, which the instance no longer applies; the skeleton's root stands in.
            warn(
                what +
                ": the node has a skin but the primitive has no JOINTS_0 and WEIGHTS_0: drawn at the skin's first joint");
            for (size_t i = 0; i < n; ++i) blended[i] = pose.joints.front(), total[i] = 1;
        }
        size_t unweighted = 0;
        normal_matrices->resize(n);
        for (size_t i = 0; i < n; ++i) {
            Eigen::Matrix4d m = total[i] > 0 ? Eigen::Matrix4d(blended[i] / total[i]) : pose.joints.front();
            unweighted += !(total[i] > 0);
            const Eigen::Vector4d q = m * mesh->positions[i].cast<double>().homogeneous();
            mesh->positions[i] = q.head<3>().cast<float>();
            const Eigen::Matrix3d linear = m.topLeftCorner<3, 3>();
            const double det = linear.determinant();
            (*normal_matrices)[i] = std::abs(det) > 1e-30 ? Eigen::Matrix3f(linear.inverse().transpose().cast<float>())
                                                          : Eigen::Matrix3f::Identity();
        }
        if (unweighted)
            warn(what + ": " + std::to_string(unweighted) +
                 " vertices have skin weights that are all zero: drawn at the skin's first joint");
    }

    // Builds one primitive, or returns false (with a warning) when it has nothing to draw.
    bool build_primitive(const tg::Primitive& p, const std::string& what, TriangleMesh* mesh,
                         const VertexPose* pose = nullptr) {
        int mode = p.mode < 0 ? TINYGLTF_MODE_TRIANGLES : p.mode;
        if (mode == TINYGLTF_MODE_POINTS || mode == TINYGLTF_MODE_LINE || mode == TINYGLTF_MODE_LINE_LOOP ||
            mode == TINYGLTF_MODE_LINE_STRIP) {
            warn(what + ": points and lines are not rendered, skipped");
            return false;
        }
        if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
            mode != TINYGLTF_MODE_TRIANGLE_FAN) {
            warn(what + ": unknown primitive mode " + std::to_string(mode) + ", skipped");
            return false;
        }
        auto attr = [&](const char* name) {
            auto it = p.attributes.find(name);
            return it == p.attributes.end() ? -1 : it->second;
        };
        if (attr("POSITION") < 0) {
            warn(what + ": no POSITION attribute, skipped");
            return false;
        }

        const int position = attr("POSITION");
        if (size_t(position) < model_.accessors.size()) {
            const int type = model_.accessors[size_t(position)].componentType;
            if (type != TINYGLTF_COMPONENT_TYPE_FLOAT && !uses_extension("KHR_mesh_quantization"))
                fail(what + " POSITION has integer components (componentType " + std::to_string(type) +
                     ") but the file does not use KHR_mesh_quantization: glTF 2.0 positions are floats");
        }
        FloatArray pos = read_floats(position, what + " POSITION", {TINYGLTF_TYPE_VEC3});
        const size_t n = pos.count;
        if (n > size_t(std::numeric_limits<uint32_t>::max())) fail(what + ": too many vertices");
        mesh->positions = to_vectors<3>(pos);
        const std::vector<double> no_weights;
        const std::vector<double>& weights = pose ? pose->morph_weights : no_weights;
        add_morph_deltas(p, weights, "POSITION", what, &mesh->positions);
        std::vector<Eigen::Matrix3f> normal_matrices;  // per vertex, when skinned
        if (pose && !pose->joints.empty()) skin_positions(p, *pose, what, mesh, &normal_matrices);
        // Embree's bounds and every intersection with a NaN or infinite vertex are meaningless (a
        // NaN poisons the whole BVH node): refused, as a corrupt file, with the first such vertex.
        for (size_t i = 0; i < n; ++i)
            if (!mesh->positions[i].allFinite())
                fail(what + " POSITION " + std::to_string(i) + " is not finite (" +
                     (mesh->positions[i].hasNaN() ? "NaN" : "infinite") + "): a corrupt file?");

        std::vector<uint32_t> stream;
        if (p.indices >= 0) {
            stream = read_accessor<uint32_t>(p.indices, what + " indices", {TINYGLTF_TYPE_SCALAR});
            for (uint32_t i : stream)
                if (i >= n)
                    fail(what + ": index " + std::to_string(i) + " is out of range (the primitive has " +
                         std::to_string(n) + " vertices)");
        } else {
            stream.resize(n);
            for (size_t i = 0; i < n; ++i) stream[i] = uint32_t(i);
        }
        mesh->indices = triangulate(mode, stream, what, p.indices >= 0);
        if (mesh->indices.empty()) {
            warn(what + ": no triangles, skipped");
            return false;
        }
        bool any_area = false;  // a primitive of zero-area triangles only is never hit: nothing to draw
        for (size_t t = 0; t + 2 < mesh->indices.size() && !any_area; t += 3) {
            const Vec3& a = mesh->positions[mesh->indices[t]];
            any_area = (mesh->positions[mesh->indices[t + 1]] - a)
                           .cross(mesh->positions[mesh->indices[t + 2]] - a)
                           .squaredNorm() > 0;
        }
        if (!any_area) {
            warn(what + ": every triangle has zero area, skipped");
            return false;
        }

        auto read_matching = [&](const char* name, std::initializer_list<int> types) {
            FloatArray f = read_floats(attr(name), what + " " + name, types);
            if (f.count != n)
                fail(what + ": " + name + " has " + std::to_string(f.count) + " elements but POSITION has " +
                     std::to_string(n));
            return f;
        };
        // Core glTF UVs are floats or normalised integers; plain integers (texel-sized UVs that
        // wrap thousands of times) need KHR_mesh_quantization, as for positions.
        for (const char* uv_name : {"TEXCOORD_0", "TEXCOORD_1"}) {
            const int a = attr(uv_name);
            if (a < 0 || size_t(a) >= model_.accessors.size()) continue;
            const tg::Accessor& acc = model_.accessors[size_t(a)];
            if (acc.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT && !acc.normalized &&
                !uses_extension("KHR_mesh_quantization"))
                fail(what + " " + uv_name + " has integer components that are not normalized (componentType " +
                     std::to_string(acc.componentType) +
                     ") but the file does not use KHR_mesh_quantization: glTF 2.0 UVs are floats or normalized");
        }
        if (attr("TEXCOORD_0") >= 0)
            mesh->texcoords[0] = to_vectors<2>(read_matching("TEXCOORD_0", {TINYGLTF_TYPE_VEC2}));
        if (attr("TEXCOORD_1") >= 0)
            mesh->texcoords[1] = to_vectors<2>(read_matching("TEXCOORD_1", {TINYGLTF_TYPE_VEC2}));
        if (attr("COLOR_0") >= 0) {
            FloatArray c = read_matching("COLOR_0", {TINYGLTF_TYPE_VEC3, TINYGLTF_TYPE_VEC4});
            mesh->colors.resize(n);
            for (size_t i = 0; i < n; ++i) {
                const float* v = &c.values[i * size_t(c.components)];
                mesh->colors[i] = Vec4(v[0], v[1], v[2], c.components == 4 ? v[3] : 1.0f);
            }
        }
        if (p.material >= 0) {
            if (size_t(p.material) >= scene_.materials.size())
                fail(what + " refers to material " + std::to_string(p.material) + ", which does not exist");
            mesh->material = p.material;
            warn_missing_uv_sets(*mesh, what);
        }

        if (attr("NORMAL") < 0) {
            // The spec: no normals means flat normals, and any TANGENT must then be ignored.
            generate_flat_normals(*mesh);
        } else {
            mesh->normals = to_vectors<3>(read_matching("NORMAL", {TINYGLTF_TYPE_VEC3}));
            add_morph_deltas(p, weights, "NORMAL", what, &mesh->normals);
            for (size_t i = 0; i < normal_matrices.size(); ++i)
                mesh->normals[i] = normal_matrices[i] * mesh->normals[i];
            bool all_valid = true;
            for (Vec3& nrm : mesh->normals) {
                float len = nrm.norm();
                if (len > 0 && std::isfinite(len)) nrm /= len;
                else all_valid = false;
            }
            if (!all_valid) {
                // Repair only the broken ones, from the area-weighted neighbourhood.
                TriangleMesh smooth;
                smooth.positions = mesh->positions, smooth.indices = mesh->indices;
                generate_smooth_normals(smooth);
                for (size_t i = 0; i < n; ++i)
                    if (!(std::abs(mesh->normals[i].squaredNorm() - 1.0f) < 1e-3f))
                        mesh->normals[i] = smooth.normals[i];
                warn(what + ": some normals were zero or not finite and were regenerated");
            }
            if (attr("TANGENT") >= 0) {
                mesh->tangents = to_vectors<4>(read_matching("TANGENT", {TINYGLTF_TYPE_VEC4}));
                if (!weights.empty() || !normal_matrices.empty()) {
                    std::vector<Vec3> xyz(n);
                    for (size_t i = 0; i < n; ++i) xyz[i] = mesh->tangents[i].head<3>();
                    add_morph_deltas(p, weights, "TANGENT", what, &xyz);
                    // Tangents are directions in the surface: the skin's linear part (the inverse
                    // transpose's inverse transpose) carries them.
                    for (size_t i = 0; i < normal_matrices.size(); ++i) {
                        xyz[i] = normal_matrices[i].inverse().transpose() * xyz[i];
                        // A joint that mirrors turns the frame's handedness (as a mirroring node does).
                        if (normal_matrices[i].determinant() < 0) mesh->tangents[i].w() = -mesh->tangents[i].w();
                    }
                    for (size_t i = 0; i < n; ++i) mesh->tangents[i].head<3>() = xyz[i];
                }
                bool tangents_valid = true;
                for (Vec4& t : mesh->tangents) {
                    float len = t.head<3>().norm();
                    if (len > 0 && std::isfinite(len)) t.head<3>() /= len;
                    else tangents_valid = false;
                    t.w() = t.w() < 0 ? -1.0f : 1.0f;
                }
                if (!tangents_valid) mesh->tangents.clear();
            }
        }
        if (mesh->tangents.empty()) {
            int texcoord = mesh->material >= 0 ? scene_.materials[size_t(mesh->material)].normal_texture.texcoord : 0;
            generate_tangents(*mesh, texcoord);
        }
        return true;
    }

    // The MeshGroup of a glTF mesh, built on first use; -1 when it has nothing to draw.
    // A posed mesh (skinned, or morphed by non-zero weights) is built for its node alone.
    int mesh_group(int mesh_index, const VertexPose* pose = nullptr) {
        if (mesh_index < 0 || size_t(mesh_index) >= model_.meshes.size())
            fail("a node refers to mesh " + std::to_string(mesh_index) + ", which does not exist");
        if (group_of_mesh_.empty()) group_of_mesh_.assign(model_.meshes.size(), kNotBuilt);
        int unshared = kNotBuilt;
        int& group = pose ? unshared : group_of_mesh_[size_t(mesh_index)];
        if (group != kNotBuilt) return group;
        const tg::Mesh& m = model_.meshes[size_t(mesh_index)];
        MeshGroup g;
        g.name = m.name.empty() ? "mesh " + std::to_string(mesh_index) : m.name;
        for (size_t k = 0; k < m.primitives.size(); ++k) {
            TriangleMesh tm;
            if (build_primitive(m.primitives[k], "mesh " + in_quotes(g.name) + " primitive " + std::to_string(k), &tm,
                                pose))
                g.primitives.push_back(std::move(tm));
        }
        if (g.primitives.empty()) return group = -1;
        scene_.meshes.push_back(std::move(g));
        return group = int(scene_.meshes.size()) - 1;
    }

    // The morph weights a node draws its mesh with (the node's, else the mesh's defaults); empty
    // when all are zero or the mesh has no targets.
    std::vector<double> morph_weights(const tg::Node& node, const std::string& what) {
        const tg::Mesh& m = model_.meshes[size_t(node.mesh)];
        size_t targets = 0;
        for (const tg::Primitive& p : m.primitives) targets = std::max(targets, p.targets.size());
        std::vector<double> w = node.weights.empty() ? m.weights : node.weights;
        if (targets == 0) return {};
        for (double x : w)
            if (!std::isfinite(x)) fail(what + ": a morph weight is not finite");
        if (!w.empty() && w.size() != targets)
            warn(what + ": " + std::to_string(w.size()) + " morph weights for " + std::to_string(targets) +
                 " morph targets: the missing ones are 0");
        if (std::all_of(w.begin(), w.end(), [](double x) { return x == 0; })) return {};
        return w;
    }

    // The joint matrices of skin `index`: each joint's world transform x its inverse bind matrix.
    std::vector<Eigen::Matrix4d> skin_joints(int index, const std::function<Eigen::Matrix4d(int)>& world_of,
                                             const std::string& what) const {
        if (index < 0 || size_t(index) >= model_.skins.size())
            fail(what + " refers to skin " + std::to_string(index) + ", which does not exist (the file has " +
                 std::to_string(model_.skins.size()) + ")");
        const tg::Skin& skin = model_.skins[size_t(index)];
        const std::string name = "skin " + std::to_string(index);
        if (skin.joints.empty()) fail(name + " has no joints");
        std::vector<float> ibm;
        if (skin.inverseBindMatrices >= 0) {
            ibm = read_accessor<float>(skin.inverseBindMatrices, name + " inverseBindMatrices", {TINYGLTF_TYPE_MAT4});
            if (ibm.size() != 16 * skin.joints.size())
                fail(name + " has " + std::to_string(ibm.size() / 16) + " inverse bind matrices for " +
                     std::to_string(skin.joints.size()) + " joints");
        }
        std::vector<Eigen::Matrix4d> joints;
        for (size_t j = 0; j < skin.joints.size(); ++j) {
            const int node = skin.joints[j];
            if (node < 0 || size_t(node) >= model_.nodes.size())
                fail(name + " joint " + std::to_string(j) + " is node " + std::to_string(node) +
                     ", which does not exist");
            Eigen::Matrix4d inverse_bind = Eigen::Matrix4d::Identity();
            if (!ibm.empty())
                for (int i = 0; i < 16; ++i) inverse_bind(i % 4, i / 4) = ibm[16 * j + size_t(i)];  // column-major
            if (!inverse_bind.allFinite()) fail(name + " inverse bind matrix " + std::to_string(j) + " is not finite");
            joints.push_back(world_of(node) * inverse_bind);
        }
        return joints;
    }

    // ---- Nodes ------------------------------------------------------------------------------

    Eigen::Matrix4d local_matrix(const tg::Node& node) const {
        // Lengths, types, affine matrices and non-zero rotations were checked on the JSON
        // (check_gltf_json): arrays of the wrong length had been read as identity.
        if (node.matrix.size() == 16) {
            Eigen::Matrix4d m;
            for (int i = 0; i < 16; ++i) m(i % 4, i / 4) = node.matrix[size_t(i)];  // column-major
            return m;
        }
        Eigen::Vector3d t = Eigen::Vector3d::Zero(), s = Eigen::Vector3d::Ones();
        Eigen::Quaterniond r = Eigen::Quaterniond::Identity();
        if (node.translation.size() == 3)
            t = Eigen::Vector3d(node.translation[0], node.translation[1], node.translation[2]);
        if (node.scale.size() == 3) s = Eigen::Vector3d(node.scale[0], node.scale[1], node.scale[2]);
        if (node.rotation.size() == 4) {
            // glTF stores (x, y, z, w); Eigen's constructor takes (w, x, y, z).
            r = Eigen::Quaterniond(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]);
            r.normalize();
        }
        return trs_matrix(t, r, s);
    }

    // EXT_mesh_gpu_instancing: per-instance TRS, applied before the node's world transform.
    std::vector<Eigen::Matrix4d> gpu_instances(const tg::Node& node, const std::string& what) {
        const tg::Value* ext = extension(node.extensions, "EXT_mesh_gpu_instancing");
        if (!ext) return {};
        const tg::Value* attributes = member(*ext, "attributes");
        auto read = [&](const char* name, int type) -> FloatArray {
            const tg::Value* a = attributes ? member(*attributes, name) : nullptr;
            if (!a || !a->IsNumber()) return {};
            return read_floats(a->GetNumberAsInt(), what + " EXT_mesh_gpu_instancing " + name, {type});
        };
        FloatArray t = read("TRANSLATION", TINYGLTF_TYPE_VEC3), r = read("ROTATION", TINYGLTF_TYPE_VEC4),
                   s = read("SCALE", TINYGLTF_TYPE_VEC3);
        size_t count = std::max({t.count, r.count, s.count});
        for (const FloatArray* f : {&t, &r, &s})
            if (f->count != 0 && f->count != count)
                fail(what + ": EXT_mesh_gpu_instancing attributes have different counts");
        if (count == 0) {
            warn(what + ": EXT_mesh_gpu_instancing without attributes, drawn once");
            return {};
        }
        std::vector<Eigen::Matrix4d> out(count);
        for (size_t i = 0; i < count; ++i) {
            Eigen::Vector3d ti = t.count ? Eigen::Vector3d(t.values[3 * i], t.values[3 * i + 1], t.values[3 * i + 2])
                                         : Eigen::Vector3d::Zero();
            Eigen::Vector3d si = s.count ? Eigen::Vector3d(s.values[3 * i], s.values[3 * i + 1], s.values[3 * i + 2])
                                         : Eigen::Vector3d::Ones();
            Eigen::Quaterniond ri = Eigen::Quaterniond::Identity();
            if (r.count) {
                ri = Eigen::Quaterniond(r.values[4 * i + 3], r.values[4 * i], r.values[4 * i + 1], r.values[4 * i + 2]);
                if (ri.norm() > 0) ri.normalize();
                else ri = Eigen::Quaterniond::Identity();
            }
            out[i] = trs_matrix(ti, ri, si);
        }
        return out;
    }

    void add_camera(const tg::Node& node, int node_index, const Eigen::Matrix4d& world) {
        if (node.camera < 0) return;
        if (size_t(node.camera) >= model_.cameras.size())
            fail("node " + std::to_string(node_index) + " refers to camera " + std::to_string(node.camera) +
                 ", which does not exist");
        const tg::Camera& c = model_.cameras[size_t(node.camera)];
        std::string name = !c.name.empty()      ? c.name
                           : !node.name.empty() ? node.name
                                                : "camera " + std::to_string(node.camera);
        if (c.type != "perspective" && c.type != "orthographic") {
            warn("camera " + in_quotes(name) + " is " + (c.type.empty() ? std::string("untyped") : c.type) +
                 ": only perspective and orthographic cameras are supported, skipped");
            return;
        }
        Camera cam;
        cam.name = name;
        // The rotation part only: a camera frame must stay orthonormal even under scaled parents, and
        // look down its node's -Z with its +Y up under a mirroring one (the spec: a camera's view
        // ignores scale). Eigen's rotation() of a mirror turned it round to look along +Z.
        // In double: a scale of 1e20 overflows a float's squared norm.
        Eigen::Affine3f w = to_affine(world);
        const Eigen::Matrix3d m = world.topLeftCorner<3, 3>();
        const Eigen::Vector3d back = m.col(2).normalized();
        const Eigen::Vector3d up = (m.col(1) - back * back.dot(m.col(1))).normalized();
        Eigen::Matrix3d frame;
        frame << up.cross(back), up, back;
        if (frame.allFinite() && std::abs(frame.determinant() - 1) < 1e-6)
            cam.camera_to_world = Eigen::Translation3f(w.translation()) * Eigen::Matrix3f(frame.cast<float>());
        else  // -Z and +Y (nearly) parallel: a sheared frame
            cam.camera_to_world = Eigen::Translation3f(w.translation()) * w.rotation();
        const double far = world.col(3).head<3>().cwiseAbs().maxCoeff();
        if (!(far <= kMaxCoordinate))
            fail("camera " + in_quotes(name) + " is " + number_text(far, 3) + " m from the origin, beyond " +
                 number_text(kMaxCoordinate, 3) + " m: single precision cannot resolve the scene from there");
        // An aspect ratio far from any image's (1e-30, 1e30) makes rays that see one pixel's worth.
        auto aspect_or_image = [&](double aspect, const char* what) {
            if (aspect == 0) return 0.0f;
            if (aspect >= 1e-3 && aspect <= 1e3) return float(aspect);
            warn("camera " + in_quotes(name) + ": " + what + " " + number_text(aspect) +
                 " is not a plausible aspect ratio, using the image's");
            return 0.0f;
        };
        if (c.type == "orthographic") {
            cam.orthographic = true;
            const double ymag = c.orthographic.ymag;
            if (!(ymag >= 1e-6 && ymag <= kMaxCoordinate)) {
                warn("camera " + in_quotes(name) + ": orthographic ymag " + number_text(ymag) + " is outside [1e-06, " +
                     number_text(kMaxCoordinate, 3) + "] m, skipped");
                return;
            }
            cam.ymag = float(ymag);
            if (c.orthographic.xmag > 0) cam.aspect_ratio = aspect_or_image(c.orthographic.xmag / ymag, "xmag / ymag");
        } else {
            // The range --fov allows (0.01 to 179.9 degrees): 1e-30 rad saw one texel's worth.
            if (c.perspective.yfov >= 0.01 * kPiD / 180 && c.perspective.yfov <= 179.9 * kPiD / 180)
                cam.yfov = float(c.perspective.yfov);
            else
                warn("camera " + in_quotes(name) + ": yfov " + number_text(c.perspective.yfov) +
                     " rad is outside 0.01 to 179.9 degrees, using the default");
            cam.aspect_ratio = c.perspective.aspectRatio > 0 ? aspect_or_image(c.perspective.aspectRatio, "aspectRatio")
                                                             : 0.0f;
        }
        cam.file_index = node.camera;
        cameras_.push_back({node.camera, node_index, std::move(cam)});
    }

    // KHR_lights_punctual: the light a node holds, placed by its world transform (position, -Z).
    void add_light(const tg::Node& node, const std::string& what, const Eigen::Matrix4d& world) {
        const tg::Value* ext = extension(node.extensions, "KHR_lights_punctual");
        if (!ext) return;
        const tg::Value* index = member(*ext, "light");
        if (!index || !index->IsNumber() || index->GetNumberAsInt() < 0 ||
            size_t(index->GetNumberAsInt()) >= model_.lights.size())
            fail(what + ": KHR_lights_punctual light " +
                 (index && index->IsNumber() ? std::to_string(index->GetNumberAsInt())
                                             : std::string("(not a number)")) +
                 " does not exist (the file has " + std::to_string(model_.lights.size()) + ")");
        const int li = index->GetNumberAsInt();
        const tg::Light& l = model_.lights[size_t(li)];
        const std::string name = "light " + (l.name.empty() ? std::to_string(li) : in_quotes(l.name));
        PunctualLight light;
        light.name = l.name.empty() ? "light " + std::to_string(li) : l.name;
        if (l.type == "point") light.type = PunctualLight::Type::Point;
        else if (l.type == "spot") light.type = PunctualLight::Type::Spot;
        else if (l.type == "directional") light.type = PunctualLight::Type::Directional;
        else fail(name + ": type " + in_quotes(l.type) + " is not point, spot or directional");
        Color colour = Color::Ones();
        if (!l.color.empty()) {
            if (l.color.size() != 3) fail(name + ": color has " + std::to_string(l.color.size()) + " numbers, not 3");
            colour = Color(float(l.color[0]), float(l.color[1]), float(l.color[2]));
            if (!(colour.minCoeff() >= 0) || !colour.allFinite())
                fail(name + ": color (" + number_text(l.color[0]) + ", " + number_text(l.color[1]) + ", " +
                     number_text(l.color[2]) + ") is not a colour (finite, non-negative)");
        }
        // 1e9 cd or lux: past any lamp and the sun (about 1.2e5 lux); more is a corrupt file.
        if (!(l.intensity >= 0 && l.intensity <= 1e9))
            fail(name + ": intensity " + number_text(l.intensity) + " is outside [0, 1e9] " +
                 (light.type == PunctualLight::Type::Directional ? "lux" : "candela"));
        if (!(l.range >= 0) || !std::isfinite(l.range))
            fail(name + ": range " + number_text(l.range) + " is not positive");
        light.intensity = colour * float(l.intensity / kLumensPerWatt);
        light.range = float(l.range);
        if (light.type == PunctualLight::Type::Spot) {
            const double inner = l.spot.innerConeAngle, outer = l.spot.outerConeAngle;
            if (!(inner >= 0 && inner < outer && outer <= kPiD / 2 + 1e-6))
                fail(name + ": spot cone angles inner " + number_text(inner) + " and outer " + number_text(outer) +
                     " rad must satisfy 0 <= inner < outer <= pi / 2");
            light.cos_inner = float(std::cos(inner)), light.cos_outer = float(std::cos(std::min(outer, kPiD / 2)));
        }
        const Eigen::Vector3d position = world.col(3).head<3>();
        if (!(position.cwiseAbs().maxCoeff() <= kMaxCoordinate))
            fail(what + ": " + name + " is " + number_text(position.cwiseAbs().maxCoeff(), 3) +
                 " m from the origin, beyond " + number_text(kMaxCoordinate, 3) + " m");
        const Eigen::Vector3d forward = -world.col(2).head<3>();
        if (!forward.allFinite()) fail(what + ": " + name + "'s world transform is not finite: it shines nowhere");
        if (!(forward.norm() > 0)) {  // a zero scale hides a light as it hides a mesh
            warn(what + ": " + name + "'s world transform has no -Z axis (a scale of 0: hidden), not used");
            return;
        }
        light.position = position.cast<float>();
        light.direction = forward.normalized().cast<float>();
        if (light.intensity.maxCoeff() > 0) scene_.lights.push_back(light);
    }

    // A texture on a UV set the primitive lacks is read at UV (0, 0): one texel over the surface.
    void warn_missing_uv_sets(const TriangleMesh& mesh, const std::string& what) {
        const Material& m = scene_.materials[size_t(mesh.material)];
        for (const TextureSlot* slot :
             {&m.base_color_texture, &m.metallic_roughness_texture, &m.transmission_texture, &m.clearcoat_texture,
              &m.clearcoat_roughness_texture, &m.specular_texture, &m.specular_color_texture, &m.sheen_color_texture,
              &m.sheen_roughness_texture, &m.normal_texture, &m.occlusion_texture, &m.emissive_texture}) {
            if (!slot->present() || !mesh.texcoords[slot->texcoord].empty()) continue;
            if (!missing_uv_warned_.insert({mesh.material, slot->texcoord}).second) continue;
            warn(what + ": material " + in_quotes(m.name.empty() ? std::to_string(mesh.material) : m.name) +
                 " maps a texture with TEXCOORD_" + std::to_string(slot->texcoord) +
                 ", which the primitive does not have: the texture is read at UV (0, 0), one texel");
        }
    }

    void traverse_nodes() {
        const size_t count = model_.nodes.size();
        std::vector<int> parent(count, -1);
        for (size_t i = 0; i < count; ++i)
            for (int c : model_.nodes[i].children) {
                if (c < 0 || size_t(c) >= count)
                    fail("node " + std::to_string(i) + " has child " + std::to_string(c) + ", which does not exist");
                if (parent[size_t(c)] >= 0)
                    fail("node " + std::to_string(c) + " has two parents (" + std::to_string(parent[size_t(c)]) +
                         " and " + std::to_string(i) + "): the node hierarchy must be a forest");
                parent[size_t(c)] = int(i);
            }

        // World transforms by the parent chain, for skins' joints wherever they lie.
        Eigen::Matrix4d root = Eigen::Matrix4d::Identity();  // what the roots hang from (the shift below)
        std::vector<Eigen::Matrix4d> world_cache(count);
        std::vector<char> world_known(count, 0);
        std::function<Eigen::Matrix4d(int)> world_of = [&](int index) -> Eigen::Matrix4d {
            std::vector<int> chain;
            for (int i = index; i >= 0 && !world_known[size_t(i)]; i = parent[size_t(i)]) {
                if (chain.size() > count) fail("node " + std::to_string(index) + " is its own ancestor (a cycle)");
                chain.push_back(i);
            }
            for (auto it = chain.rbegin(); it != chain.rend(); ++it) {
                const int p = parent[size_t(*it)];
                world_cache[size_t(*it)] = (p >= 0 ? world_cache[size_t(p)] : root) *
                                           local_matrix(model_.nodes[size_t(*it)]);
                world_known[size_t(*it)] = 1;
            }
            return world_cache[size_t(index)];
        };

        std::vector<int> roots;
        if (!model_.scenes.empty()) {
            int s = model_.defaultScene;
            if (s < 0 || size_t(s) >= model_.scenes.size()) s = 0;
            roots = model_.scenes[size_t(s)].nodes;
            if (model_.scenes.size() > 1)
                warn("the file has " + std::to_string(model_.scenes.size()) + " scenes: rendering scene " +
                     std::to_string(s));
        } else {
            for (size_t i = 0; i < count; ++i)
                if (parent[i] < 0) roots.push_back(int(i));
            if (!roots.empty()) warn("the file has no scenes: rendering every root node");
        }

        std::vector<char> visited(count, 0);
        std::vector<std::pair<int, Eigen::Matrix4d>> stack;
        for (auto it = roots.rbegin(); it != roots.rend(); ++it) {
            if (*it < 0 || size_t(*it) >= count)
                fail("the scene refers to node " + std::to_string(*it) + ", which does not exist");
            stack.emplace_back(*it, Eigen::Matrix4d::Identity());
        }
        // A scene placed far from the origin by its nodes (georeferenced: site coordinates in
        // kilometres) is moved near it before anything is rounded to float, by whole metres: 100 km
        // out a float resolves 8 mm, 1000 km out 6 cm, and shadows, contacts and thin walls went
        // wrong. The node transforms are doubles, so nothing is lost; cameras, lights and skins
        // move with it, --look-at by Scene::origin_shift.
        {
            Bounds3 nodes;
            std::vector<int> todo(roots);
            std::vector<char> seen(count, 0);
            while (!todo.empty()) {
                const int i = todo.back();
                todo.pop_back();
                if (i < 0 || size_t(i) >= count || seen[size_t(i)]) continue;  // reported by the walk below
                seen[size_t(i)] = 1;
                const tg::Node& node = model_.nodes[size_t(i)];
                if (node.mesh >= 0 || node.camera >= 0) {
                    const Eigen::Vector3d t = world_of(i).col(3).head<3>();
                    if (t.allFinite()) nodes.extend(t.cast<float>());
                }
                for (int c : node.children) todo.push_back(c);
            }
            const Eigen::Vector3d centre = nodes.empty() ? Eigen::Vector3d::Zero()
                                                         : Eigen::Vector3d(nodes.center().cast<double>());
            if (centre.cwiseAbs().maxCoeff() > kRecentreBeyond && centre.cwiseAbs().maxCoeff() <= kMaxCoordinate) {
                scene_.origin_shift = centre.array().round().matrix();
                root.col(3).head<3>() = -scene_.origin_shift;
                world_known.assign(count, 0);
                for (auto& entry : stack) entry.second = root;
            }
        }
        while (!stack.empty()) {
            auto [index, parent_world] = stack.back();
            stack.pop_back();
            if (visited[size_t(index)])
                fail("node " + std::to_string(index) +
                     " is reached twice (a cycle, or listed in the scene as well as a child)");
            visited[size_t(index)] = 1;
            const tg::Node& node = model_.nodes[size_t(index)];
            Eigen::Matrix4d world = parent_world * local_matrix(node);
            std::string what = "node " + (node.name.empty() ? std::to_string(index) : in_quotes(node.name));
            auto check_transform = [&](const Eigen::Matrix4d& m, const std::string& which) {
                if (std::string problem = transform_problem(m); !problem.empty())
                    fail(which + ": its world transform " + problem);
            };
            if (node.mesh >= int(model_.meshes.size()))
                fail(what + " refers to mesh " + std::to_string(node.mesh) + ", which does not exist");
            const bool collapsed = node.mesh >= 0 && node.skin < 0 && transform_collapses(world);
            if (collapsed) {
                warn(what + ": its world transform scales it to a point or a line (a scale of 0: hidden), not drawn");
                ++scene_.hidden_meshes;
            }
            if (node.mesh >= 0 && !collapsed) {
                VertexPose pose;
                pose.morph_weights = morph_weights(node, what);
                if (node.skin >= 0) pose.joints = skin_joints(node.skin, world_of, what);
                const bool posed = !pose.morph_weights.empty() || !pose.joints.empty();
                int group = mesh_group(node.mesh, posed ? &pose : nullptr);
                if (group >= 0 && !pose.joints.empty()) {
                    // Skinned vertices are in world space: the spec ignores the mesh node's transform.
                    scene_.instances.push_back({group, Eigen::Affine3f::Identity()});
                } else if (group >= 0) {
                    std::vector<Eigen::Matrix4d> instances = gpu_instances(node, what);
                    if (instances.empty()) {
                        check_transform(world, what);
                        scene_.instances.push_back({group, to_affine(world)});
                    } else {
                        for (size_t i = 0; i < instances.size(); ++i) {
                            if (transform_collapses(world * instances[i])) {  // hidden, as a node can be
                                warn(what + " instance " + std::to_string(i) +
                                     ": scaled to a point or a line (a scale of 0: hidden), not drawn");
                                ++scene_.hidden_meshes;
                                continue;
                            }
                            check_transform(world * instances[i], what + " instance " + std::to_string(i));
                            scene_.instances.push_back({group, to_affine(world * instances[i])});
                        }
                    }
                }
            }
            if (node.camera >= 0 && !world.topRows<3>().cast<float>().allFinite())
                fail(what + ": the camera's world transform is not finite");
            if (node.camera >= 0 && !(std::abs(world.topLeftCorner<3, 3>().determinant()) > 1e-30))
                fail(what + ": the camera's world transform is singular (a zero scale?): it has no view direction");
            add_camera(node, index, world);
            add_light(node, what, world);
            for (auto c = node.children.rbegin(); c != node.children.rend(); ++c) stack.emplace_back(*c, world);
        }
        // Cameras in the order of the file's cameras array (then of the nodes that use them).
        std::stable_sort(cameras_.begin(), cameras_.end(), [](const NodeCamera& a, const NodeCamera& b) {
            return std::tie(a.camera_index, a.node_index) < std::tie(b.camera_index, b.node_index);
        });
        for (NodeCamera& c : cameras_) scene_.cameras.push_back(std::move(c.camera));
        scene_.file_camera_names.clear();
        for (size_t k = 0; k < model_.cameras.size(); ++k)
            scene_.file_camera_names.push_back(model_.cameras[k].name.empty() ? "camera " + std::to_string(k)
                                                                              : model_.cameras[k].name);
    }

    static constexpr double kMaxCoordinate = kMaxSceneCoordinate;  // metres from the origin (scene.h)
    static constexpr double kRecentreBeyond = 1000;                // metres: nearer, floats resolve 0.1 mm
    void check_extent() const {
        const Bounds3 b = scene_.world_bounds();
        if (b.empty()) return;
        const double far = std::max(double(b.lo.cwiseAbs().maxCoeff()), double(b.hi.cwiseAbs().maxCoeff()));
        if (!(far <= kMaxCoordinate))
            fail("geometry reaches " + number_text(far, 3) + " m from the origin, beyond " +
                 number_text(kMaxCoordinate, 3) +
                 " m: single precision cannot resolve it (units not metres? georeferenced? move it near the origin)");
    }

    static constexpr int kNotBuilt = -2;
    struct NodeCamera {
        int camera_index, node_index;
        Camera camera;
    };

    const std::string path_;
    const double animation_time_;
    const std::string animation_;  // the one animation played (name or index); empty: all
    std::vector<bool> playing_;    // per animation of the file
    tg::Model model_;
    std::vector<tg::Node> rest_nodes_;  // the nodes as the file has them, before any pose
    Scene scene_;
    std::vector<std::string> warnings_;
    std::vector<int> group_of_mesh_;
    std::map<TextureRequest, int> texture_of_request_;
    std::set<std::pair<int, int>> missing_uv_warned_;  // (material, UV set) already said
    std::vector<TextureRequest> requests_;
    std::vector<NodeCamera> cameras_;
};

AnimatedGltf::AnimatedGltf(const std::string& path, const std::string& animation)
    : loader_(std::make_unique<GltfLoader>(path, 0.0, animation)) {
    loader_->load_once();
}

AnimatedGltf::~AnimatedGltf() = default;

Scene AnimatedGltf::pose(double animation_time) {
    if (!std::isfinite(animation_time) || animation_time < 0)
        throw Error("the animation time must be a finite number of seconds, at least 0");
    return loader_->pose(animation_time);
}


Scene load_gltf(const std::string& path, std::vector<std::string>* warnings, double animation_time,
                const std::string& animation) {
    if (!std::isfinite(animation_time)) throw Error("the animation time must be a finite number of seconds");
    Scene scene = GltfLoader(path, animation_time, animation).load();
    if (warnings) warnings->insert(warnings->end(), scene.warnings.begin(), scene.warnings.end());
    return scene;
}

}  // namespace dynsky
