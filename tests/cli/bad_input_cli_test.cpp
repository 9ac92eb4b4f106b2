// The bad-input corpus of issue 12, generated here at test time (small files in a temporary
// folder): every case must end in a non-zero exit, a message naming the file (or the option) and
// the problem, and no file written (the folder's listing is unchanged: no output, no .tmp-*).
// One test per class of bad input; each also runs a good input through the same command, so a
// test fails if the command refuses everything.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <future>
#include <limits>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include "tests/test_support.h"
#include "util/data_path.h"
#include "util/image.h"

namespace dynsky {
namespace {

namespace fs = std::filesystem;

// Every case runs under `timeout`: a hang (a FIFO read) fails the test instead of blocking it.
test::CommandResult dynsky(const std::string& args) {
    return test::run_command("timeout 60 " + std::string(DYNSKY_EXE) + " " + args);
}

std::set<std::string> listing(const std::string& dir) {
    std::set<std::string> names;
    for (const auto& e : fs::recursive_directory_iterator(dir)) names.insert(e.path().string());
    return names;
}

std::string read_bytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void write_bytes(const std::string& path, const std::string& bytes) { std::ofstream(path, std::ios::binary) << bytes; }

// The bad inputs of one class, run a few at a time (dynsky's start-up dominates their cost) once
// all are written, then checked: a non-zero exit (not a crash or a timeout), an error naming every
// string in `says`, and nothing new in `dir` (no output, no temporary file).
class Refusals {
  public:
    explicit Refusals(std::string dir) : dir_(std::move(dir)) {}
    // Option errors come from CLI11's parser ("--threads: '-1' is not a number in 0 .. 4096"): `error_line`
    // false skips the "dynsky: error:" check for them.
    void add(const std::string& args, const std::vector<std::string>& says, bool error_line = true) {
        cases_.push_back({args, says, error_line});
    }
    // Returns the outputs, in the order the cases were added.
    std::vector<std::string> check() {
        const std::set<std::string> before = listing(dir_);
        std::vector<std::string> outputs;
        for (size_t first = 0; first < cases_.size(); first += 4) {
            std::vector<std::future<test::CommandResult>> runs;
            for (size_t k = first; k < std::min(first + 4, cases_.size()); ++k)
                runs.push_back(std::async(std::launch::async, [args = cases_[k].args] { return dynsky(args); }));
            for (size_t k = first; k < std::min(first + 4, cases_.size()); ++k) {
                const Case& c = cases_[k];
                test::CommandResult r = runs[k - first].get();
                SCOPED_TRACE("dynsky " + c.args);
                EXPECT_NE(r.exit_code, 0) << r.output;
                EXPECT_LT(r.exit_code, 124) << "crashed or timed out:\n" << r.output;
                if (c.error_line) {  // a runtime error (exit 1) or an option's (exit 2), said as such
                    const char* label = r.exit_code == 2 ? "dynsky: usage error: " : "dynsky: error: ";
                    EXPECT_NE(r.output.find(label), std::string::npos) << r.output;
                }
                for (const std::string& s : c.says)
                    EXPECT_NE(r.output.find(s), std::string::npos) << "should say '" << s << "':\n" << r.output;
                outputs.push_back(r.output);
            }
        }
        EXPECT_EQ(listing(dir_), before) << "refused runs left files behind";
        EXPECT_GE(cases_.size(), 3u);
        return outputs;
    }

  private:
    struct Case {
        std::string args;
        std::vector<std::string> says;
        bool error_line;
    };
    std::string dir_;
    std::vector<Case> cases_;
};

void expect_accepted(const std::string& args) {
    test::CommandResult r = dynsky(args);
    EXPECT_EQ(r.exit_code, 0) << "dynsky " << args << "\n" << r.output;
}

// ---- Small valid inputs ------------------------------------------------------------------------

// A uniform sky EXR, n x n (float pixels), optionally with one pixel changed.
std::string sky_exr(const std::string& path, int n = 16, float value = 1.0f, int px = -1, float pixel = 0.0f) {
    Image im(n, n, 3);
    for (float& v : im.pixels) v = value;
    if (px >= 0)
        for (int c = 0; c < 3; ++c) im.at(px, px, c) = pixel;
    write_image(path, im);
    return path;
}

// An 8-bit image (PNG/JPEG by extension) of a smooth gradient, w x h.
std::string ldr_image(const std::string& path, int w, int h) {
    Image im(w, h, 3);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c) im.at(x, y, c) = float((x * 7 + y * 3 + c * 50) % 255) / 255.0f;
    write_image(path, im);
    return path;
}

const char* kTriangleBin = "tri.bin";

// DIR/tri.bin: one triangle (3 float positions).
void write_triangle_bin(const std::string& dir) {
    const float p[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    write_bytes(dir + "/" + kTriangleBin, std::string(reinterpret_cast<const char*>(p), sizeof p));
}

// A glTF drawing the triangle from its nodes. `nodes`: the nodes array, node 0 the root;
// `buffer_uri`: where the triangle's bytes are; `image_uri`: when set, a textured material.
std::string triangle_gltf(const std::string& path, const std::string& nodes = R"([{"mesh":0}])",
                          const std::string& buffer_uri = kTriangleBin, const std::string& image_uri = "") {
    std::string material = image_uri.empty() ? "" : R"(,"material":0)";
    std::string json = R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":)" + nodes +
                       R"(,"meshes":[{"primitives":[{"attributes":{"POSITION":0})" + material + R"(}]}],)" +
                       R"("buffers":[{"uri":")" + buffer_uri + R"(","byteLength":36}],)" +
                       R"("bufferViews":[{"buffer":0,"byteLength":36}],)" +
                       R"("accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3",)" +
                       R"("min":[0,0,0],"max":[1,1,0]}])";
    if (!image_uri.empty())
        json += R"(,"materials":[{"pbrMetallicRoughness":{"baseColorTexture":{"index":0}}}],)"
                R"("textures":[{"source":0}],"images":[{"uri":")" +
                image_uri + R"("}])";
    write_bytes(path, json + "}");
    return path;
}

std::string render_args(const std::string& scene, const std::string& dir, const std::string& extra = "") {
    return "render " + scene + " --res 8x6 --spp 1 -q -o " + dir + "/out.exr " + extra;
}

// ---- Patching image headers ------------------------------------------------------------------

void put_be32(std::string* b, size_t i, uint32_t v) {
    for (int k = 0; k < 4; ++k) (*b)[i + k] = char(v >> (24 - 8 * k));
}
void put_le32(std::string* b, size_t i, uint32_t v) {
    for (int k = 0; k < 4; ++k) (*b)[i + k] = char(v >> (8 * k));
}

// A PNG chunk with its CRC.
std::string png_chunk(const std::string& type, const std::string& data) {
    std::string c(4, '\0');
    put_be32(&c, 0, uint32_t(data.size()));
    c += type + data;
    std::string crc(4, '\0');
    put_be32(&crc, 0, uint32_t(crc32(0, reinterpret_cast<const Bytef*>(c.data() + 4), uInt(c.size() - 4))));
    return c + crc;
}

// A valid PNG whose IHDR now says w x h (CRC fixed, so only the size is wrong).
std::string patch_png_size(const std::string& png, uint32_t w, uint32_t h) {
    std::string b = png;
    put_be32(&b, 16, w), put_be32(&b, 20, h);
    std::string crc(4, '\0');
    put_be32(&crc, 0, uint32_t(crc32(0, reinterpret_cast<const Bytef*>(b.data() + 12), 17)));
    b.replace(29, 4, crc);
    return b;
}

// A valid grey PNG of w x h zero pixels: a decompression bomb (a few hundred kB for 289 Mpixels).
std::string png_bomb(uint32_t w, uint32_t h) {
    std::string ihdr(13, '\0');
    put_be32(&ihdr, 0, w), put_be32(&ihdr, 4, h);
    ihdr[8] = 8;  // bit depth; colour type 0 (grey), no interlace
    z_stream z{};
    deflateInit(&z, Z_BEST_COMPRESSION);
    std::vector<unsigned char> row(size_t(w) + 1, 0), out(1 << 16);
    std::string idat;
    for (uint32_t y = 0; y < h; ++y) {
        z.next_in = row.data(), z.avail_in = uInt(row.size());
        int flush = y + 1 == h ? Z_FINISH : Z_NO_FLUSH;
        do {
            z.next_out = out.data(), z.avail_out = uInt(out.size());
            deflate(&z, flush);
            idat.append(reinterpret_cast<char*>(out.data()), out.size() - z.avail_out);
        } while (z.avail_out == 0);
    }
    deflateEnd(&z);
    return std::string("\x89PNG\r\n\x1a\n", 8) + png_chunk("IHDR", ihdr) + png_chunk("IDAT", idat) +
           png_chunk("IEND", "");
}

// A valid baseline JPEG whose frame header now says w x h.
std::string patch_jpeg_size(const std::string& jpeg, uint16_t w, uint16_t h) {
    std::string b = jpeg;
    size_t sof = b.find("\xFF\xC0");
    if (sof == std::string::npos) return "";
    b[sof + 5] = char(h >> 8), b[sof + 6] = char(h & 255), b[sof + 7] = char(w >> 8), b[sof + 8] = char(w & 255);
    return b;
}

// An uncompressed 16 x 16 EXR whose data and display windows now say w x h, with a line-offset
// table of h entries so that OpenEXR opens it: a valid header for a huge image (h * 8 bytes).
std::string huge_exr(const std::string& scratch, uint32_t w, uint32_t h) {
    {
        OIIO::ImageSpec spec(16, 16, 3, OIIO::TypeDesc::FLOAT);
        spec.attribute("compression", "none");
        std::vector<float> px(16 * 16 * 3, 1.0f);
        auto out = OIIO::ImageOutput::create(scratch);
        if (!out || !out->open(scratch, spec)) return "";
        out->write_image(OIIO::TypeDesc::FLOAT, px.data());
        out->close();
    }
    std::string b = read_bytes(scratch);
    fs::remove(scratch);
    for (const char* name : {"dataWindow", "displayWindow"}) {
        size_t at = b.find(std::string(name) + '\0' + "box2i" + '\0');
        if (at == std::string::npos) return "";
        size_t box = at + std::strlen(name) + 1 + 6 + 4;  // name, type, size
        put_le32(&b, box, 0), put_le32(&b, box + 4, 0), put_le32(&b, box + 8, w - 1), put_le32(&b, box + 12, h - 1);
    }
    // The header's attributes (name, type, size, value) end with a zero byte; the table follows.
    size_t p = 8;
    while (p < b.size() && b[p] != '\0') {
        size_t type = b.find('\0', p) + 1, size = b.find('\0', type) + 1;
        uint32_t n = uint32_t((unsigned char)b[size]) | uint32_t((unsigned char)b[size + 1]) << 8 |
                     uint32_t((unsigned char)b[size + 2]) << 16 | uint32_t((unsigned char)b[size + 3]) << 24;
        p = size + 4 + n;
    }
    b.insert(p + 1, std::string(size_t(h - 16) * 8, '\0'));  // zero offsets: OpenEXR rebuilds the table
    return b;
}

// ---- 1. Crashes: deep JSON, singular or non-finite transforms --------------------------------

TEST(BadInputCli, DeeplyNestedGltfJsonIsRefusedBeforeParsing) {
    const std::string dir = test::temp_dir("bad");
    Refusals bad(dir);
    write_triangle_bin(dir);
    expect_accepted(render_args(triangle_gltf(dir + "/ok.gltf"), dir));
    fs::remove(dir + "/out.exr"), fs::remove(dir + "/out.png");
    std::string base = read_bytes(dir + "/ok.gltf");
    struct Case {
        std::string name, open, close;
        int depth;
    } cases[] = {{"arrays20000.gltf", "[", "]", 20000},
                 {"objects20000.gltf", "{\"a\":", "}", 20000},
                 {"mixed5000.gltf", "[{\"x\":", "}]", 2500},
                 {"arrays300.gltf", "[", "]", 300}};
    for (const Case& c : cases) {
        std::string deep;
        for (int i = 0; i < c.depth; ++i) deep += c.open;
        deep += "1";
        for (int i = 0; i < c.depth; ++i) deep += c.close;
        // In the asset's extras, where a loader keeps any JSON it does not know.
        std::string json = base;
        json.replace(json.find("\"asset\":{"), 9, "\"asset\":{\"extras\":" + deep + ",");
        write_bytes(dir + "/" + c.name, json);
        bad.add(render_args(dir + "/" + c.name, dir), {c.name, "nested", "levels deep"});
    }
    // The same in a GLB's JSON chunk, and before a syntax error (depth is checked first).
    std::string deep(20000, '[');
    std::string json = "{\"asset\":{\"version\":\"2.0\",\"extras\":" + deep + "1" + std::string(20000, ']') + "}}";
    while (json.size() % 4) json += ' ';
    std::string glb = "glTF" + std::string(16, '\0') + json;
    put_le32(&glb, 4, 2), put_le32(&glb, 8, uint32_t(glb.size())), put_le32(&glb, 12, uint32_t(json.size()));
    glb.replace(16, 4, "JSON");
    write_bytes(dir + "/deep.glb", glb);
    bad.add(render_args(dir + "/deep.glb", dir), {"deep.glb", "levels deep"});
    write_bytes(dir + "/unclosed.gltf", "{\"asset\":" + std::string(30000, '['));
    bad.add(render_args(dir + "/unclosed.gltf", dir), {"unclosed.gltf", "levels deep"});
    bad.check();
}

TEST(BadInputCli, SingularOrNonFiniteNodeTransformsAreRefused) {
    const std::string dir = test::temp_dir("bad");
    Refusals bad(dir);
    write_triangle_bin(dir);
    expect_accepted(render_args(triangle_gltf(dir + "/ok.gltf", R"([{"mesh":0,"scale":[2,2,2]}])"), dir));
    fs::remove(dir + "/out.exr"), fs::remove(dir + "/out.png");
    struct Case {
        const char* name;
        const char* nodes;
        const char* says;
    } cases[] = {
        // (A scale of 0 on every axis, or all but one, hides the node: skipped, not refused; a plane
        // cannot be instanced.)
        {"scale0", R"([{"mesh":0,"scale":[0,1,1]}])", "singular"},
        {"flat_axis", R"([{"mesh":0,"scale":[1,0,1]}])", "singular"},
        {"tiny", R"([{"mesh":0,"scale":[1e-30,1e-30,1e-30]}])", "singular"},
        {"nested_huge", R"([{"children":[1],"scale":[1e200,1e200,1e200]},{"mesh":0,"scale":[1e200,1e200,1e200]}])",
         "not finite"},
        {"beyond_float", R"([{"mesh":0,"translation":[1e39,0,0]}])", "not finite"},
        {"rank2_matrix", R"([{"mesh":0,"matrix":[1,0,0,0,0,1,0,0,1,1,0,0,0,0,0,1]}])", "singular"},
        {"parent_scale0", R"([{"children":[1],"scale":[0,1,1]},{"mesh":0}])", "singular"},
        {"huge_det", R"([{"mesh":0,"scale":[1e12,1e12,1e12]}])", "singular"},
    };
    for (const Case& c : cases) {
        std::string file = std::string(c.name) + ".gltf";
        triangle_gltf(dir + "/" + file, c.nodes);
        bad.add(render_args(dir + "/" + file, dir), {file, "node", "world transform", c.says});
    }
    bad.check();
}

TEST(BadInputCli, NonFiniteVertexPositionsAreRefused) {
    const std::string dir = test::temp_dir("bad");
    Refusals bad(dir);
    const float inf = std::numeric_limits<float>::infinity(), nan = std::numeric_limits<float>::quiet_NaN();
    struct Case {
        const char* name;
        int component;  // of the 9 floats of the triangle
        float value;
        const char* says;
    } cases[] = {{"nan_x", 0, nan, "POSITION 0 is not finite (NaN)"},
                 {"inf_y", 4, inf, "POSITION 1 is not finite (infinite)"},
                 {"minus_inf_z", 8, -inf, "POSITION 2 is not finite (infinite)"}};
    for (const Case& c : cases) {
        float p[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
        p[c.component] = c.value;
        const std::string bin = std::string(c.name) + ".bin", file = std::string(c.name) + ".gltf";
        write_bytes(dir + "/" + bin, std::string(reinterpret_cast<const char*>(p), sizeof p));
        triangle_gltf(dir + "/" + file, R"([{"mesh":0}])", bin);
        bad.add(render_args(dir + "/" + file, dir), {file, c.says});
    }
    bad.check();
}

// ---- 2. Hangs: FIFO and directory URIs --------------------------------------------------------

TEST(BadInputCli, UrisThatAreNotRegularFilesAreRefused) {
    const std::string dir = test::temp_dir("bad");
    Refusals bad(dir);
    write_triangle_bin(dir);
    ldr_image(dir + "/tex.png", 8, 8);
    expect_accepted(render_args(triangle_gltf(dir + "/ok.gltf", R"([{"mesh":0}])", kTriangleBin, "tex.png"), dir));
    fs::remove(dir + "/out.exr"), fs::remove(dir + "/out.png");
    ASSERT_EQ(::mkfifo((dir + "/pipe.bin").c_str(), 0600), 0);
    ASSERT_EQ(::mkfifo((dir + "/pipe.png").c_str(), 0600), 0);
    fs::create_directories(dir + "/folder.bin");
    fs::create_directories(dir + "/folder.png");
    fs::create_symlink("pipe.bin", dir + "/link_to_pipe.bin");
    struct Case {
        const char* name;
        const char* buffer;
        const char* image;
    } cases[] = {{"fifo_buffer", "pipe.bin", ""},       {"fifo_image", kTriangleBin, "pipe.png"},
                 {"dir_buffer", "folder.bin", ""},      {"dir_image", kTriangleBin, "folder.png"},
                 {"link_fifo", "link_to_pipe.bin", ""}, {"dot_buffer", ".", ""}};
    for (const Case& c : cases) {
        std::string file = std::string(c.name) + ".gltf";
        triangle_gltf(dir + "/" + file, R"([{"mesh":0}])", c.buffer, c.image);
        bad.add(render_args(dir + "/" + file, dir), {file, "not a regular file"});
    }
    // Images read directly (skies, photos, masks) too.
    bad.add(render_args("builtin", dir, "--sky " + dir + "/pipe.png"), {"pipe.png", "not a regular file"});
    bad.add("sky import " + dir + "/pipe.png -o " + dir + "/s.exr", {"pipe.png", "not a regular file"});
    bad.add("sky procedural --duration 0 --sky-res 16 -o " + dir + "/p --mask-image " + dir + "/pipe.png",
            {"pipe.png", "not a regular file"});
    bad.check();
}

// ---- 3. Security: URIs confined to the asset's folder -----------------------------------------

TEST(BadInputCli, UrisOutsideTheAssetFolderAreRefused) {
    const std::string root = test::temp_dir("bad");
    Refusals bad(root);
    const std::string dir = root + "/asset";
    fs::create_directories(dir + "/sub");
    write_triangle_bin(dir);
    write_triangle_bin(root);  // a real file just outside the asset's folder
    ldr_image(root + "/outside.png", 8, 8);
    fs::create_symlink(root + "/" + kTriangleBin, dir + "/escape.bin");
    fs::create_symlink(root, dir + "/up");
    fs::create_symlink(dir + "/" + kTriangleBin, dir + "/inside_link.bin");
    // Relative links and `sub/..` that stay inside are fine.
    expect_accepted(render_args(triangle_gltf(dir + "/ok.gltf", R"([{"mesh":0}])", "sub/../inside_link.bin"), root));
    fs::remove(root + "/out.exr"), fs::remove(root + "/out.png");
    struct Case {
        const char* name;
        const char* buffer;
        const char* image;
        const char* says;
    } cases[] = {
        {"passwd", "../../../../../../etc/passwd", "", "leaves the asset's folder"},
        {"parent", "../tri.bin", "", "leaves the asset's folder"},
        {"sub_up", "sub/../../tri.bin", "", "leaves the asset's folder"},
        {"encoded", "%2e%2e/%2e%2e/etc/passwd", "", "leaves the asset's folder"},
        {"absolute", "/etc/passwd", "", "absolute"},
        {"file_url", "file:///etc/passwd", "", "absolute"},
        {"dev_zero", "/dev/zero", "", "absolute"},
        {"symlink_out", "escape.bin", "", "outside the asset's folder"},
        {"dir_link_out", "up/tri.bin", "", "outside the asset's folder"},
        {"image_up", kTriangleBin, "../outside.png", "leaves the asset's folder"},
        {"image_abs", kTriangleBin, "/etc/hostname", "absolute"},
    };
    for (const Case& c : cases) {
        std::string file = std::string(c.name) + ".gltf";
        triangle_gltf(dir + "/" + file, R"([{"mesh":0}])", c.buffer, c.image);
        bad.add(render_args(dir + "/" + file, root), {file, "URI", c.says});
    }
    bad.check();
}

// ---- 4. Memory: sizes from headers checked before allocation -----------------------------------

TEST(BadInputCli, HugeImageHeadersAreRefusedBeforeAllocation) {
    const std::string dir = test::temp_dir("bad");
    Refusals bad(dir);
    const std::string src = dir + "/src";
    fs::create_directories(src);
    std::string png = read_bytes(ldr_image(src + "/s.png", 16, 16));
    std::string jpg = read_bytes(ldr_image(src + "/s.jpg", 16, 16));
    ASSERT_FALSE(huge_exr(src + "/s.exr", 30000, 30000).empty());
    ASSERT_FALSE(patch_jpeg_size(jpg, 60000, 60000).empty());
    write_bytes(dir + "/huge.exr", huge_exr(src + "/s.exr", 30000, 30000));  // 243 kB asking for 10.8 GB
    write_bytes(dir + "/wide.exr", huge_exr(src + "/s.exr", 100000, 16));    // one side too long
    write_bytes(dir + "/big.exr", huge_exr(src + "/s.exr", 16384, 16384));   // 2^28 pixels but 3 * 2^28 values
    fs::remove_all(src);
    write_bytes(dir + "/huge.png", patch_png_size(png, 40000, 40000));
    write_bytes(dir + "/tall.png", patch_png_size(png, 1, 900000));     // within libpng's own limit of 10^6
    write_bytes(dir + "/wide.png", patch_png_size(png, 20000, 10000));  // within stb's own limit of 2^30 bytes
    write_bytes(dir + "/huge.jpg", patch_jpeg_size(jpg, 60000, 60000));
    write_bytes(dir + "/bomb.png", png_bomb(17000, 17000));
    EXPECT_LT(fs::file_size(dir + "/bomb.png"), 2u << 20);
    const std::vector<std::string> files = {"huge.exr", "wide.exr", "big.exr",  "huge.png",
                                            "tall.png", "wide.png", "huge.jpg", "bomb.png"};
    for (const std::string& f : files) {
        const std::string path = dir + "/" + f;
        const std::vector<std::string> says = {f, "beyond what dynsky reads"};
        bad.add("sky import " + path + " -o " + dir + "/s.exr", says);
        bad.add("sky procedural --duration 0 --sky-res 16 -o " + dir + "/p --mask-image " + path, says);
        if (f.find(".exr") != std::string::npos) {
            bad.add(render_args("builtin", dir, "--sky " + path), says);
            bad.add("sky latlong " + path + " -o " + dir + "/ll.exr", says);
        }
    }
    // Textures decoded by stb inside the glTF loader: the header is read first.
    write_triangle_bin(dir);
    for (const char* f : {"wide.png", "huge.jpg", "bomb.png", "tall.png"}) {
        std::string file = "tex_" + std::string(f).substr(0, std::string(f).find('.')) + ".gltf";
        triangle_gltf(dir + "/" + file, R"([{"mesh":0}])", kTriangleBin, f);
        bad.add(render_args(dir + "/" + file, dir), {file, f, "beyond what dynsky reads"});
    }
    // Accessors without a bufferView (all zeros) bounded by the file's data.
    std::string gltf = read_bytes(triangle_gltf(dir + "/ok.gltf"));
    gltf.replace(gltf.find(R"("bufferView":0,"componentType":5126,"count":3)"), 45,
                 R"("componentType":5126,"count":268435456)");
    write_bytes(dir + "/zeros.gltf", gltf);
    bad.add(render_args(dir + "/zeros.gltf", dir), {"zeros.gltf", "accessor 0", "without a bufferView"});
    bad.check();
}

// ---- 5. Silent wrong results ------------------------------------------------------------------

TEST(BadInputCli, IntegerImagesAreNotTakenAsRadianceSkies) {
    const std::string dir = test::temp_dir("bad");
    Refusals bad(dir);
    expect_accepted("sky latlong " + sky_exr(dir + "/ok.exr") + " -o " + dir + "/ll.exr");
    fs::remove(dir + "/ll.exr"), fs::remove(dir + "/ok.exr");
    ldr_image(dir + "/png8.png", 16, 16);
    ldr_image(dir + "/jpg8.jpg", 16, 16);
    fs::copy_file(dir + "/png8.png", dir + "/png_named.exr");
    fs::copy_file(dir + "/jpg8.jpg", dir + "/jpg_named.exr");
    {
        OIIO::ImageSpec spec(16, 16, 3, OIIO::TypeDesc::UINT16);
        std::vector<uint16_t> px(16 * 16 * 3, 30000);
        auto out = OIIO::ImageOutput::create(dir + "/png16.png");
        ASSERT_TRUE(out && out->open(dir + "/png16.png", spec));
        out->write_image(OIIO::TypeDesc::UINT16, px.data());
        out->close();
    }
    for (const char* f : {"png8.png", "jpg8.jpg", "png_named.exr", "jpg_named.exr", "png16.png"}) {
        const std::string path = dir + "/" + f;
        const std::vector<std::string> says = {f, "not linear radiance", "dynsky sky import"};
        bad.add(render_args("builtin", dir, "--sky " + path), says);
        bad.add("sky latlong " + path + " -o " + dir + "/ll.exr", says);
        // animate names the file and points at the importer (it wants an .exr name first).
        if (std::string(f) == "png8.png" || std::string(f) == "jpg_named.exr")
            bad.add("animate builtin --sky " + path + " --duration 1 --fps 1 --res 8x6 --spp 1 --no-video -q -o " +
                        dir + "/anim",
                    {f, "dynsky sky import"});
    }
    bad.check();
}

TEST(BadInputCli, ImplausibleSkyRadianceIsRefusedWithItsPixel) {
    const std::string dir = test::temp_dir("bad");
    Refusals bad(dir);
    expect_accepted("sky latlong " + sky_exr(dir + "/sun.exr", 16, 1.0f, 8, 2e7f) + " -o " + dir + "/ll.exr");
    fs::remove(dir + "/ll.exr"), fs::remove(dir + "/sun.exr");
    sky_exr(dir + "/1e35.exr", 16, 1.0f, 5, 1e35f);
    sky_exr(dir + "/1e10.exr", 16, 1.0f, 7, 1e10f);
    sky_exr(dir + "/max.exr", 16, 1.0f, 3, 3.4e38f);
    for (const char* f : {"1e35.exr", "1e10.exr", "max.exr"}) {
        const std::string path = dir + "/" + f;
        std::string pos = std::string(f) == "1e35.exr" ? "(5, 5)" : std::string(f) == "1e10.exr" ? "(7, 7)" : "(3, 3)";
        const std::vector<std::string> says = {f, "sky pixel " + pos, "above the limit"};
        bad.add(render_args("builtin", dir, "--sky " + path), says);
        bad.add("sky latlong " + path + " -o " + dir + "/ll.exr", says);
        bad.add("sky mask " + path + " -o " + dir + "/m.png", says);
    }
    bad.check();
}

TEST(BadInputCli, TruncatedOrCorruptImagesFail) {
    const std::string dir = test::temp_dir("bad");
    Refusals bad(dir);
    std::string jpg = read_bytes(ldr_image(dir + "/photo.jpg", 64, 48));
    std::string png = read_bytes(ldr_image(dir + "/photo.png", 64, 48));
    std::string exr = read_bytes(sky_exr(dir + "/sky.exr", 64));
    expect_accepted("sky mask " + dir + "/photo.jpg --whole-image -o " + dir + "/m.png");
    fs::remove(dir + "/m.png");
    for (const char* f : {"photo.jpg", "photo.png", "sky.exr"}) fs::remove(dir + "/" + f);
    struct Case {
        std::string name, bytes;
    } cases[] = {{"cut10.jpg", jpg.substr(0, jpg.size() / 10)},    {"cut50.jpg", jpg.substr(0, jpg.size() / 2)},
                 {"cut_end.jpg", jpg.substr(0, jpg.size() - 2)},   {"cut50.png", png.substr(0, png.size() / 2)},
                 {"cut_end.png", png.substr(0, png.size() - 20)},  {"cut50.exr", exr.substr(0, exr.size() / 2)},
                 {"cut90.exr", exr.substr(0, exr.size() * 9 / 10)}};
    for (const Case& c : cases) {
        write_bytes(dir + "/" + c.name, c.bytes);
        const std::string path = dir + "/" + c.name;
        bad.add("sky mask " + path + " --whole-image -o " + dir + "/m.png", {c.name});
        bad.add("sky import " + path + " -o " + dir + "/s.exr", {c.name});
    }
    for (const char* f : {"cut50.png", "cut50.exr"})
        bad.add("sky procedural --duration 0 --sky-res 16 -o " + dir + "/p --mask-image " + dir + "/" + f, {f});
    // The decoder's own report of a JPEG cut short (or, when it is silent, dynsky's marker walk).
    std::vector<std::string> outputs = bad.check();
    for (size_t k = 0; k < 6; k += 2)  // the JPEG cases, through `sky mask`
        EXPECT_TRUE(outputs[k].find("Premature end") != std::string::npos ||
                    outputs[k].find("cut short") != std::string::npos)
            << outputs[k];
}

TEST(BadInputCli, MultiPartExrIsRefused) {
    const std::string dir = test::temp_dir("bad");
    Refusals bad(dir);
    const std::string path = dir + "/parts.exr";
    {
        OIIO::ImageSpec specs[2] = {OIIO::ImageSpec(16, 16, 3, OIIO::TypeDesc::FLOAT),
                                    OIIO::ImageSpec(16, 16, 3, OIIO::TypeDesc::FLOAT)};
        std::vector<float> px(16 * 16 * 3, 1.0f);
        auto out = OIIO::ImageOutput::create(path);
        ASSERT_TRUE(out);
        ASSERT_TRUE(out->supports("multiimage"));
        ASSERT_TRUE(out->open(path, 2, specs));
        out->write_image(OIIO::TypeDesc::FLOAT, px.data());
        ASSERT_TRUE(out->open(path, specs[1], OIIO::ImageOutput::AppendSubimage));
        out->write_image(OIIO::TypeDesc::FLOAT, px.data());
        out->close();
    }
    const std::vector<std::string> says = {"parts.exr", "has 2 parts"};
    bad.add(render_args("builtin", dir, "--sky " + path), says);
    bad.add("sky latlong " + path + " -o " + dir + "/ll.exr", says);
    bad.add("sky import " + path + " -o " + dir + "/s.exr", says);
    bad.add("sky procedural --duration 0 --sky-res 16 -o " + dir + "/p --mask-image " + path, says);
    bad.check();
}

TEST(BadInputCli, ModelDescriptionsWithoutTheirFormatOrVersionAreRefused) {
    const std::string dir = test::temp_dir("bad");
    Refusals bad(dir);
    const std::string sky = sky_exr(dir + "/in.exr", 32);
    struct Case {
        const char* name;
        const char* json;
        const char* says;
    } cases[] = {
        {"no_format", R"({"version":2,"kind":"advect-residual","resolution":64,"dt_s":30})", "\"format\" is missing"},
        {"wrong_format", R"({"format":"onnx-zoo","version":2,"kind":"advect-residual"})", "\"format\" is \"onnx-zoo\""},
        {"no_version", R"({"format":"dynsky-cloud-model","kind":"advect-residual"})", "\"version\" is missing"},
        {"text_version", R"({"format":"dynsky-cloud-model","version":"2","kind":"advect-residual"})",
         "\"version\" is \"2\""},
        {"future_version",
         R"({"format":"dynsky-cloud-model","version":7,"kind":"advect-residual","resolution":64,"dt_s":30})",
         "version 7"},
        {"paper_version", R"({"format":"dynsky-cloud-model","version":2,"resolution":64,"dt_s":30,"flow_scale":0.08})",
         "version 2"},
        {"not_object", R"([1,2,3])", "not a model description"},
    };
    for (const Case& c : cases) {
        const std::string folder = dir + "/" + c.name;
        fs::create_directories(folder);
        write_bytes(folder + "/model.json", c.json);
        bad.add("sky predict --model " + folder + " --sky " + sky + " --steps 1 -q -o " + dir + "/pred",
                {c.name + std::string("/model.json"), c.says});
    }
    // A model whose networks do not run at its model.json's resolution: named, not an OpenCV assertion.
    for (const std::string shipped : {"advect_residual", "arm_tsi"}) {
        const std::string folder = dir + "/resized_" + shipped;
        fs::create_directories(folder);
        for (const auto& e : fs::directory_iterator(data_path("networks/models/" + shipped)))
            if (e.path().extension() == ".onnx") fs::copy_file(e.path(), folder + "/" + e.path().filename().string());
        std::string json = read_bytes(data_path("networks/models/" + shipped + "/model.json"));
        size_t at = json.find("\"resolution\": 64");
        ASSERT_NE(at, std::string::npos);
        json.replace(at, 16, "\"resolution\": 32");
        write_bytes(folder + "/model.json", json);
        bad.add("sky predict --model " + folder + " --sky " + sky + " --steps 1 -q -o " + dir + "/pred",
                {"resized_" + shipped, ".onnx: does not run on the input model.json describes"});
    }
    bad.check();
}

// ---- 7. OpenCV assertions become errors naming the file ----------------------------------------

TEST(BadInputCli, PhotographsOfOddSizesFailNamingTheFile) {
    const std::string dir = test::temp_dir("bad");
    Refusals bad(dir);
    struct Case {
        const char* name;
        int w, h;
    } cases[] = {{"one.jpg", 1, 1},       {"row.jpg", 3000, 1}, {"column.png", 1, 2000},
                 {"sliver.jpg", 16, 400}, {"tiny.png", 8, 8},   {"narrow.jpg", 15, 64}};
    for (const Case& c : cases) {
        const std::string path = ldr_image(dir + "/" + c.name, c.w, c.h);
        const std::string size = std::to_string(c.w) + " x " + std::to_string(c.h);
        bad.add("sky import " + path + " -o " + dir + "/s.exr", {c.name, size});
        if (c.w == 1 || c.h == 1) bad.add("sky mask " + path + " -o " + dir + "/m.png", {c.name, size});
    }
    bad.check();
}

// ---- 6. Options -------------------------------------------------------------------------------

// Found by a bad-input audit (ninth session): each exited 0 with garbage, hung, or crashed.
TEST(BadInputCli, AuditedInputsAreRefusedClearly) {
    const std::string dir = test::temp_dir("bad");
    Refusals bad(dir);
    // A sky so faint its light underflows single precision: rendered black, exit 0.
    bad.add(render_args("builtin", dir, "--sky " + sky_exr(dir + "/faint.exr", 16, 1e-30f)),
            {"faint.exr", "too faint to light with"});
    // Emission beyond the glTF spec's ranges (1e39 overflowed to infinity and rendered black).
    write_triangle_bin(dir);
    std::string gltf = read_bytes(triangle_gltf(dir + "/tri.gltf"));
    gltf.pop_back();
    write_bytes(dir + "/emissive.gltf",
                gltf + R"(,"materials":[{"emissiveFactor":[1,1,1],"extensions":{"KHR_materials_emissive_strength":)"
                       R"({"emissiveStrength":1e39}}}],"extensionsUsed":["KHR_materials_emissive_strength"]})");
    std::string with_material = read_bytes(dir + "/emissive.gltf");
    const std::string attributes = R"("attributes":{"POSITION":0})";
    with_material.replace(with_material.find(attributes), attributes.size(), attributes + R"(,"material":0)");
    write_bytes(dir + "/emissive.gltf", with_material);
    write_bytes(dir + "/dark.gltf",
                gltf + R"(,"materials":[{"pbrMetallicRoughness":{"baseColorFactor":[-1,0,0,1]}}]})");
    bad.add(render_args(dir + "/emissive.gltf", dir), {"emissive.gltf", "material 0", "emissive_strength 1e+39"});
    bad.add(render_args(dir + "/dark.gltf", dir),
            {"dark.gltf", "baseColorFactor -1 is negative (the spec's range is [0, 1])"});
    // An emissive factor above 1 is kept (older exporters), an absurd one refused saying where
    // brighter emission belongs (it said "outside [0, 1]" of a value it accepts up to 1e6).
    write_bytes(dir + "/bright.gltf", gltf + R"(,"materials":[{"emissiveFactor":[2e6,0,0]}]})");
    bad.add(render_args(dir + "/bright.gltf", dir),
            {"bright.gltf", "emissiveFactor", "KHR_materials_emissive_strength"});
    // A sky circle off the photograph: the whole sky was invented by inpainting, exit 0.
    const std::string photo = ldr_image(dir + "/photo.png", 200, 160);
    bad.add("sky import " + photo + " --center 5000,5000 --radius 100 -o " + dir + "/s.exr",
            {"photo.png", "of the sky disc is seen sky"});
    // An HDR photograph of absurd values: imported, then refused only by render.
    bad.add("sky import " + sky_exr(dir + "/huge.exr", 64, 1e31f) + " --center 32,32 --radius 30 -o " + dir + "/s.exr",
            {"huge.exr", "pixel (0, 0) is 1e+31, far beyond any light"});
    // The preview and the filled mask asked into one file: one silently replaced the other.
    bad.add("sky import " + photo + " --center 100,80 --radius 70 -o " + dir + "/s.exr --preview " + dir +
                "/p.png --filled-mask " + dir + "/p.png",
            {"--filled-mask", "the same file as --preview"});
    // A medium step of a nanosecond: hung (a billion steps).
    bad.add(
        "animate builtin --sky procedural --sky-res 32 --duration 1 --fps 2 --dt 1e-9 --res 8x6 --spp 1 -q "
        "--no-video -o " +
            dir + "/anim",
        {"--duration 1 s at a medium step of 1e-09 s (--dt)", "more than the 100000"});
    // A bad --time is a usage error naming the option (exit 2).
    bad.add("sky clear --lat 0 --lon 0 --time 2026-13-01T00:00:00Z -o " + dir + "/c.exr", {"--time", "month 13"},
            false);
    // The render's PNG cannot be written (a folder of its name): no EXR left, and a reason, not
    // "Success".
    fs::create_directories(dir + "/busy/out.png");
    bad.add("render builtin --res 8x6 --spp 1 -q -o " + dir + "/busy/out.exr",
            {"out.png", "a folder of that name is in the way"});
    // An input (or the --stats CSV) named as one of the numbered files the command writes into
    // --out: it was overwritten (full-disk audit).
    fs::create_directories(dir + "/named");
    const std::string step = sky_exr(dir + "/named/step_0001.exr"), frame = sky_exr(dir + "/named/frame_0000.exr");
    const std::string named = "has the name of one of the files this command writes into";
    bad.add("sky predict --sky " + step + " --steps 1 -q -o " + dir + "/named",
            {step, "is an input of this prediction and one of the steps it writes"});
    bad.add("sky predict --sky " + frame + " --steps 2 -q -o " + dir + "/p --stats " + dir + "/p/step_0002.png",
            {"step_0002.png", named});
    bad.add("animate builtin --sky " + frame + " --res 8x6 --spp 1 --duration 1 --fps 1 -q --no-video -o " + dir +
                "/named",
            {frame, named, "(frame_NNNN)"});
    bad.add("sky procedural --sky-res 32 --duration 10 --mask-image " + frame + " -q -o " + dir + "/named",
            {frame, named});
    // The report and its CSV would be one file.
    bad.add("sky evaluate --photos " + dir + "/named --resolutions 64 -o " + dir + "/ev.csv",
            {"the report is Markdown", "ev.md"});
    const std::vector<std::string> outputs = bad.check();
    EXPECT_NE(outputs[7].find("usage error"), std::string::npos) << outputs[7];
    EXPECT_FALSE(fs::exists(dir + "/busy/out.exr"));
    fs::remove_all(dir);
}

TEST(BadInputCli, OutOfRangeNumericOptionsAreRefusedNamingTheOption) {
    const std::string dir = test::temp_dir("bad");
    Refusals bad(dir);
    const std::string sky = sky_exr(dir + "/sky.exr", 16);
    const std::string photo = ldr_image(dir + "/photo.jpg", 64, 48);
    const std::string r = "render builtin --res 8x6 --spp 1 -q -o " + dir + "/out.exr ";
    const std::string a = "animate builtin --sky clear --sky-res 16 --res 8x6 --spp 1 --no-video -q -o " + dir +
                          "/anim ";
    const std::string p = "sky procedural --duration 0 --sky-res 16 -o " + dir + "/p ";
    const std::string c = "sky clear --lat 48 --lon 2 --time 2026-06-21T12:00:00Z -o " + dir + "/c.exr ";
    const std::string l = "sky latlong " + sky + " -o " + dir + "/ll.exr ";
    const std::string i = "sky import " + photo + " -o " + dir + "/s.exr ";
    struct Case {
        std::string args, option;
    } cases[] = {
        {r + "--threads -1", "--threads"},
        {r + "--seed -1", "--seed"},
        {r + "--exposure inf", "--exposure"},
        {r + "--exposure nan", "--exposure"},
        {r + "--spp 0", "--spp"},
        {r + "--spp 2.5", "--spp"},
        {r + "--max-depth -1", "--max-depth"},
        {r + "--ground-albedo 2", "--ground-albedo"},
        {r + "--camera -3", "--camera"},
        {"render builtin --spp 1 -q -o " + dir + "/out.exr --res 99999999999x5", "--res"},
        {"render builtin --spp 1 -q -o " + dir + "/out.exr --res 0x5", "--res"},
        {a + "--duration 1e9 --fps 24", "--duration"},
        {a + "--duration inf", "--duration"},
        {a + "--duration -5", "--duration"},
        {a + "--duration 1 --fps 0", "--fps"},
        {a + "--duration 1 --fps nan", "--fps"},
        {a + "--duration 1 --fps 1 --frames 99999999999999999999", "--frames"},
        {a + "--duration 1 --fps 8 --frames 5-3", "the first frame comes after the last"},
        {"render builtin --spp 1 -q -o " + dir + "/out.exr --seed 18446744073709551616", "--seed"},
        {a + "--duration 1 --fps 1 --coverage 1.5", "--coverage"},
        {a + "--duration 1 --fps 1 --wind-speed -3", "--wind-speed"},
        {a + "--duration 1 --fps 1 --cloud-height 0", "--cloud-height"},
        {a + "--duration 1 --fps 1 --dt nan", "--dt"},
        {a + "--duration 1 --fps 1 --sky procedural:99999999999999999999999", "--sky"},
        {p + "--seed -1", "--seed"},
        {p + "--coverage 2", "--coverage"},
        {p + "--dt 0", "--dt"},
        // The old spelling of --cloud-height, with its range (it kept "above 0": 1e-308 passed).
        {p + "--cumulus-altitude 1e-308", "--cumulus-altitude: '1e-308' is outside [10, 100000]"},
        {p + "--sky-res 4", "--sky-res"},
        {p + "--turbidity 0", "--turbidity"},
        {p + "--visibility -1", "--visibility"},
        {p + "--sun-elevation 100", "--sun-elevation"},
        {c + "--lat 91", "--lat"},
        {c + "--lon 360.5", "--lon"},
        // A place for a sky file, which keeps its sun (ignored before, without a word).
        {r + "--sky " + sky + " --lat -33.9 --lon 151.2", "--lat"},
        {c + "--turbidity nan", "--turbidity"},
        {c + "--sky-res 99999999999", "--sky-res"},
        {l + "--width -2", "--width"},
        {l + "--width 7", "--width"},
        {i + "--preset arm-tsi --radius 0", "--radius"},
        {i + "--radius -5 --center 32,24", "--radius"},
        {i + "--tilt inf", "--tilt"},
        {i + "--sky-res 3", "--sky-res"},
        {"sky mask " + photo + " -o " + dir + "/m.png --cloud-threshold nan", "--cloud-threshold"},
        {"compare builtin --sky clear -o " + dir + "/cmp --chart-frames 1", "--chart-frames"},
    };
    for (const Case& k : cases) bad.add(k.args, {k.option}, false);
    bad.check();
}

// A name not on an option's list is a usage error naming the option (exit 2), as --hdr and --model
// were: --sampler, --lens, --encoding, --preset, --rule, --cloud-rule and --samplers failed with exit 1
// after starting; --mask-layout without --mask was taken silently.
TEST(BadInputCli, NamesNotOnAnOptionsListAreUsageErrors) {
    const std::string dir = test::temp_dir("bad_names");
    const std::string photo = ldr_image(dir + "/photo.jpg", 64, 48);
    const std::vector<std::pair<std::string, std::string>> cases = {
        {"render builtin --res 8x6 --spp 1 -q -o " + dir + "/r.exr --sampler bogus", "--sampler"},
        {"sky import " + photo + " -o " + dir + "/s.exr --lens fisheye", "--lens"},
        {"sky import " + photo + " -o " + dir + "/s.exr --encoding rec709", "--encoding"},
        {"sky import " + photo + " -o " + dir + "/s.exr --preset gopro", "--preset"},
        {"sky import " + photo + " -o " + dir + "/s.exr --mask-layout tsi", "--mask"},
        // Options that contradict each other (one was dropped silently: an options audit).
        {"sky import " + photo + " -o " + dir + "/s.exr --no-inpaint --fill smooth", "--no-inpaint excludes --fill"},
        {"sky clear --sky-res 16 -o " + dir + "/c.exr --no-refraction --pressure 900", "--no-refraction excludes"},
        {"sky mask " + photo + " -o " + dir + "/m.png --cloud-rule blue", "--cloud-rule"},
        {"sky mask " + photo + " -o " + dir + "/m.png --preset gopro", "--preset"},
        {"sky evaluate --photos " + dir + " --preset gopro", "--preset"},
        {"sky training-data --sequence arm-tsi --out " + dir + "/td --cloud-rule blue", "--cloud-rule"},
        {"bench sampling --samplers cdf,bogus --out " + dir + "/b", "--samplers"},
    };
    std::vector<std::future<test::CommandResult>> runs;
    for (const auto& c : cases) runs.push_back(std::async(std::launch::async, [a = c.first] { return dynsky(a); }));
    for (size_t k = 0; k < cases.size(); ++k) {
        const test::CommandResult r = runs[k].get();
        SCOPED_TRACE("dynsky " + cases[k].first);
        EXPECT_EQ(r.exit_code, 2) << r.output;
        EXPECT_NE(r.output.find("dynsky: usage error: " + cases[k].second), std::string::npos) << r.output;
    }
    EXPECT_FALSE(fs::exists(dir + "/r.exr") || fs::exists(dir + "/s.exr") || fs::exists(dir + "/m.png"));
    fs::remove_all(dir);
}

// The third audit (2026-12-03): a wind that moves the clouds infinitely far per step crashed the
// warp (sky predict took any wind; animate any cloud height above 0; a model's dt_s of 1e308), a
// procedural wind or evolution beyond range wrote NaN flows, an empty value read as 0, a 7-number
// --look-at lost its first number, another camera's photographs imported with a preset's circle.
TEST(BadInputCli, ThirdAuditsWindsEmptyValuesAndOtherCamerasAreRefused) {
    const std::string dir = test::temp_dir("bad_third");
    const std::string sky = sky_exr(dir + "/sky.exr", 64);
    // The shipped advect-residual model with one field of its model.json replaced.
    auto model_with = [&](const std::string& name, const std::string& field, const std::string& value) {
        const std::string folder = dir + "/" + name;
        fs::create_directories(folder);
        std::string json = read_bytes(data_path("networks/models/advect_residual/model.json"));
        const size_t at = json.find(field);
        EXPECT_NE(at, std::string::npos) << field;
        json.replace(at, field.size(), value);
        write_bytes(folder + "/model.json", json);
        fs::copy_file(data_path("networks/models/advect_residual/model.onnx"), folder + "/model.onnx");
        return folder;
    };
    const std::string model = model_with("model_dt", "\"dt_s\": 30.0", "\"dt_s\": 1e308");
    const std::string model_base = model_with("model_base", "\"base\": \"compensated\"", "\"base\": \"weird\"");
    const std::string model_onnx = model_with("model_onnx", "\"onnx_file\": \"model.onnx\"",
                                              "\"onnx_file\": \"../../etc/passwd\"");
    const std::string photo = ldr_image(dir + "/photo.jpg", 640, 480);  // the TSI's are 480 x 640
    Refusals bad(dir);
    const std::string p = "sky predict --sky " + sky + " --steps 2 -q -o " + dir + "/p ";
    for (const char* o :
         {"--wind-speed 1e308", "--wind-from 1e308", "--cloud-height 1e-308", "--wind-speed -12", "--prev-dt nan"})
        bad.add(p + "--model advect " + o, {std::string(o).substr(0, std::string(o).find(' '))}, false);
    bad.add(p + "--model " + model, {"model.json", "dt_s"});
    bad.add(p + "--model " + model_base, {"model_base/model.json", "base 'weird'"});
    bad.add(p + "--model " + model_onnx, {"model_onnx/model.json", "onnx_file"});
    bad.add(
        "animate builtin --sky clear --sky-res 16 --res 8x6 --spp 1 --no-video -q --model advect --duration 0.2 "
        "--fps 10 -o " +
            dir + "/a --cloud-height 1e-308",
        {"--cloud-height"}, false);
    bad.add("animate builtin --sky clear --sky-res 16 --res 8x6 --spp 1 --no-video -q --duration 0.1 --fps 10 -o " +
                dir + "/a --look-at 5,5,5,0,0,0,1",
            {"--look-at takes 6 numbers", "(got 7)"}, false);
    const std::string proc = "sky procedural --sky-res 32 --duration 10 --dt 10 -q -o " + dir + "/proc ";
    bad.add(proc + "--wind 1e308,270", {"--wind"}, false);
    bad.add(proc + "--cirrus-wind nan,270", {"--cirrus-wind"}, false);
    bad.add(proc + "--evolution 1e-308", {"--evolution"}, false);
    bad.add("render builtin --res 8x6 --spp 1 -q -o " + dir + "/r.exr --time-limit ''",
            {"--time-limit: an empty value"}, false);
    bad.add("render builtin --res 8x6 -q -o " + dir + "/r.exr --spp=", {"--spp: an empty value"}, false);
    bad.add("compare builtin --sky clear -q -o " + dir + "/cmp --chart-res 0x0", {"--chart-res"}, false);
    bad.add("sky import " + photo + " --preset arm-tsi -q -o " + dir + "/s.exr",
            {"photo.jpg", "640 x 480", "the arm-tsi preset's sky circle was measured on 480 x 640"});
    bad.add("sky predict --sky " + sky + " -q -o " + dir + "/p --model advect --steps 1e308",
            {"--steps: '1e308' is not a value of this option"}, false);
    bad.add("render builtin --spp 1 -q -o " + dir + "/r.exr --res 8x6 --res 9x6", {"--res: given 2 times"}, false);
    bad.add("sky sun --lat 48 --lon 2 --time 0201-06-21T12:00:00Z", {"--time", "year 201 is outside 1800-2200"}, false);
    bad.add("render builtin --res 8x6 --spp 1 -q -o " + dir + "/r.exr --sky " + sky_exr(dir + "/tiny.exr", 2),
            {"tiny.exr", "too small to hold a sky"});
    bad.check();
    // Their good neighbours still run.
    expect_accepted(p + "--model advect --wind-speed 300 --cloud-height 10");
    expect_accepted(proc + "--wind 20,90 --evolution 1");
    // A lat-long made by `sky latlong` keeps its sky's sun: compare (which needs one) takes it.
    expect_accepted("sky clear --lat 48 --lon 2 --time 2026-06-21T12:00:00Z --sky-res 64 -q -o " + dir + "/c.exr");
    expect_accepted("sky latlong " + dir + "/c.exr --width 128 -q -o " + dir + "/ll.exr");
    // And -q silences its report as every command's (compare's went on to stderr).
    const test::CommandResult quiet = dynsky("compare builtin --sky " + dir +
                                             "/ll.exr --res 32x18 --spp 1 --chart-frames 2 --chart-res 16x9 -q -o " +
                                             dir + "/cmp_ll");
    EXPECT_EQ(quiet.exit_code, 0) << quiet.output;
    EXPECT_EQ(quiet.output, "") << "-q: nothing but warnings and errors";
    // Its images say what they are, as render's do (they were written bare).
    for (const char* name : {"clear.exr", "cloudy.exr"}) {
        Image im = read_image(dir + "/cmp_ll/" + name);
        EXPECT_EQ(im.metadata.strings["dynsky:scene"], "builtin") << name;
        EXPECT_EQ(im.metadata.numbers["dynsky:spp"], 1) << name;
        EXPECT_GT(im.metadata.numbers["dynsky:sun_y"], 0) << name;
    }
    // The side-by-side enlarged (8 x for 32 px halves) with a caption strip under it.
    const Image side = read_image(dir + "/cmp_ll/side_by_side.png");
    EXPECT_EQ(side.width, (2 * 32 + 8) * 8);
    EXPECT_EQ(side.height, 18 * 8 + 22);
    fs::remove_all(dir);
}

// A fourth audit (file contents): compare and animate with a 4 x 4 sky wrote their first outputs
// and then failed without naming the sky; `sky mask --preset` took photographs `sky import` refuses
// (another camera's size, 8 x 8, all black: half of a black photo was called cloud).
TEST(BadInputCli, FourthAuditsTinyMovingSkiesAndMaskPhotosAreRefusedFirst) {
    const std::string dir = test::temp_dir("bad_fourth");
    const std::string tiny = sky_exr(dir + "/tiny.exr", 4);
    const std::string other_camera = ldr_image(dir + "/other.jpg", 640, 480);  // the TSI's are 480 x 640
    const std::string small = ldr_image(dir + "/small.jpg", 8, 8);
    Image black(480, 640, 3);
    write_image(dir + "/black.png", black);
    Refusals bad(dir);
    bad.add("compare builtin --sky " + tiny +
                " --model advect --duration 2 --chart-frames 2 --res 16x9 --spp 1 "
                "--chart-res 16x9 -q -o " +
                dir + "/cmp",
            {"tiny.exr", "at least 8 x 8"});
    bad.add("animate builtin --sky " + tiny + " --duration 20 --fps 0.5 --res 16x9 --spp 1 --no-video -q -o " + dir +
                "/anim",
            {"tiny.exr", "at least 8 x 8"});
    bad.add("sky mask " + other_camera + " --preset arm-tsi -o " + dir + "/m1.png",
            {"other.jpg", "was measured on 480 x 640"});
    bad.add("sky mask " + small + " --preset arm-tsi -o " + dir + "/m2.png", {"small.jpg", "too small"});
    // The smaller subcommands' audit: --radius alone was ignored, a circle off the photograph read as
    // a black photograph, --whole-image silently dropped the preset's circle and masks.
    bad.add("sky mask " + other_camera + " --radius 200 -o " + dir + "/m3.png", {"--radius needs --center"});
    bad.add("sky mask " + other_camera + " --center 5000,5000 --radius 100 -o " + dir + "/m4.png",
            {"other.jpg", "holds none of the photograph's 640 x 480 pixels"});
    bad.add("sky mask " + other_camera + " --preset arm-tsi --whole-image -o " + dir + "/m5.png",
            {"--whole-image classifies every pixel", "--preset"});
    bad.add("sky mask " + dir + "/black.png --preset arm-tsi -o " + dir + "/m3.png", {"black.png", "black everywhere"});
    bad.add("animate builtin --sky " + dir +
                "/nowhere.exr --duration 10 --fps 0.2 --res 16x9 --spp 1 --no-video -q "
                "-o " +
                dir + "/a2",
            {"nowhere.exr", "no such sky file", "'procedural[:SEED]'"});
    bad.add("animate builtin --sky " + small + " --duration 10 --fps 0.2 --res 16x9 --spp 1 --no-video -q -o " + dir +
                "/a3",
            {"small.jpg", "integer pixels", "sky import"});
    bad.check();
    // A float sky in another file format is taken by animate as render takes it (it was refused as
    // "not a sky EXR"); images that are not float skies in a captured sequence's folder are named.
    {
        auto out = OIIO::ImageOutput::create(dir + "/sky.hdr");  // Radiance RGBE: float pixels
        ASSERT_TRUE(out);
        const OIIO::ImageSpec spec(32, 32, 3, OIIO::TypeDesc::FLOAT);
        const std::vector<float> px(32 * 32 * 3, 0.5f);
        ASSERT_TRUE(out->open(dir + "/sky.hdr", spec));
        ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, px.data()));
        out->close();
    }
    expect_accepted("animate builtin --sky " + dir +
                    "/sky.hdr --duration 10 --fps 0.2 --res 16x9 --spp 1 --no-video "
                    "-q -o " +
                    dir + "/a4");
    fs::create_directories(dir + "/seq");
    sky_exr(dir + "/seq/a.exr", 32);
    ldr_image(dir + "/seq/b.png", 32, 32);
    // The preview and filled mask `sky import` writes beside a sky are its own, not left out.
    ldr_image(dir + "/seq/a.png", 32, 32);
    ldr_image(dir + "/seq/a.filled.png", 32, 32);
    test::CommandResult r = dynsky("animate builtin --sky " + dir +
                                   "/seq --duration 10 --fps 0.2 --res 16x9 --spp 1 "
                                   "--no-video -q -o " +
                                   dir + "/a5");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("1 image(s) that are not float skies ignored (b.png)"), std::string::npos) << r.output;
    fs::remove_all(dir);
}

// Out of memory (a memory limit, ulimit -v, as a farm node or container sets): OpenCV's failed
// allocation came through as its raw text ("OpenCV(4.6.0) ./modules/core/src/alloc.cpp:73: error:
// (-4:Insufficient memory)..."), naming no input; bad_alloc's message listed options the command
// does not have. Now one message naming the command, its input files and sizes, and what to make
// smaller. Not under the sanitizers (their shadow memory needs terabytes of address space).
TEST(BadInputCli, OutOfMemorySaysWhatItWasAskedToHold) {
    if (test::small_run()) GTEST_SKIP() << "ulimit -v and the sanitizers' shadow memory do not mix";
    const std::string dir = test::temp_dir("oom");
    auto r = dynsky("sky clear --lat 48.85 --lon 2.35 --time 2026-06-21T12:00:00Z --sky-res 2048 -q -o " + dir +
                    "/big.exr");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    r = test::run_command("ulimit -v 900000; timeout 120 " + std::string(DYNSKY_EXE) + " sky predict --sky " + dir +
                          "/big.exr --steps 1 -q -o " + dir + "/p 2>&1");
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find("out of memory in 'sky predict'"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("big.exr ("), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("OpenCV("), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir + "/p/step_0001.exr"));
    fs::remove_all(dir);
}

}  // namespace
}  // namespace dynsky
