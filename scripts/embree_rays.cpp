// Embree's own cost per ray on path-tracing rays, outside genpath: single rays against
// 16-wide packets, a robust scene against a plain one, and any Embree build (Debian's, or
// the one inside Mitsuba's wheel). A tool for people (reports/profile.md, issue 28), never
// built by cargo, the tests or CI. Embree 3's API (Debian 12).
//
//   g++ -O2 scripts/embree_rays.cpp -o /tmp/embree_rays -lembree3
//   /tmp/embree_rays scenes/cbox/cbox.obj [PIXELS [SPP]]
//
// Against Mitsuba's Embree (its symbols live in the namespace `mitsuba`):
//   M=$(python3 -c "import mitsuba,os;print(os.path.dirname(mitsuba.__file__))")
//   g++ -O2 -DMITSUBA_EMBREE -I$M/include scripts/embree_rays.cpp $M/libembree3.so
//       -Wl,-rpath,$M -o /tmp/embree_rays_mi           (one command line)
//
// The rays are those of a diffuse path tracer in the Cornell box of scenes/cbox (its camera
// and its ceiling light are written below): PIXELS² pixels (128), SPP paths each (16), five
// bounces with cosine-weighted directions, a shadow ray to a uniform point on the light at
// every vertex, roulette with probability 0.3 from the fourth vertex. They are generated once
// (robust single rays) and then replayed, timed, in two orders: one ray per call
// (`rtcIntersect1`/`rtcOccluded1`, as genpath's `pt` traces), and as packets of the 16 paths
// of consecutive samples at the same depth (`rtcIntersect16`/`rtcOccluded16`, incoherent
// flag, ended paths masked off), as Mitsuba's LLVM variant groups its wavefront.
#include <embree3/rtcore.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#ifdef MITSUBA_EMBREE
using namespace mitsuba;
#endif

namespace {

struct Mesh {
    std::vector<float> positions;  // x, y, z per vertex
    std::vector<unsigned> indices; // three per triangle (polygons fanned)
};

// The `v` and `f` lines of an OBJ file (faces of any size, fanned into triangles).
bool load_obj(const char *path, Mesh &mesh) {
    std::ifstream in(path);
    if (!in) return false;
    std::string line;
    while (std::getline(in, line)) {
        std::istringstream s(line);
        std::string tag;
        s >> tag;
        if (tag == "v") {
            float x, y, z;
            s >> x >> y >> z;
            mesh.positions.insert(mesh.positions.end(), {x, y, z});
        } else if (tag == "f") {
            std::vector<unsigned> face;
            std::string corner;
            while (s >> corner) face.push_back(unsigned(std::atoi(corner.c_str()) - 1));
            for (size_t i = 1; i + 1 < face.size(); ++i)
                mesh.indices.insert(mesh.indices.end(), {face[0], face[i], face[i + 1]});
        }
    }
    return !mesh.indices.empty();
}

RTCScene build(RTCDevice device, const Mesh &mesh, bool robust) {
    RTCScene scene = rtcNewScene(device);
    rtcSetSceneFlags(scene, robust ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE);
    rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    size_t nv = mesh.positions.size() / 3, nt = mesh.indices.size() / 3;
    void *v = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 12, nv);
    void *t = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, nt);
    std::memcpy(v, mesh.positions.data(), 12 * nv);
    std::memcpy(t, mesh.indices.data(), 12 * nt);
    rtcCommitGeometry(g);
    rtcAttachGeometry(scene, g);
    rtcReleaseGeometry(g);
    rtcCommitScene(scene);
    return scene;
}

struct Ray {
    float o[3], d[3], tfar;
    bool live;
};

uint64_t state = 0x9E3779B97F4A7C15ull;
float uniform() {
    state ^= state << 13, state ^= state >> 7, state ^= state << 17;
    return float(state >> 40) * (1.0f / 16777216.0f);
}

void normalize(float *v) {
    float n = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (int k = 0; k < 3; ++k) v[k] /= n;
}

const int DEPTH = 5;

// Traces the paths once, robust single rays, keeping each depth's closest-hit and shadow
// rays in (pixel, sample) order.
void generate(RTCScene scene, long paths, int pixels, int spp, std::vector<Ray> closest[],
              std::vector<Ray> shadow[]) {
    const float tan_half = std::tan(39.3077f / 2 * 3.14159265f / 180);
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    for (int d = 0; d < DEPTH; ++d) closest[d].assign(paths, Ray{}), shadow[d].assign(paths, Ray{});
    for (long p = 0; p < paths; ++p) {
        long pixel = p / spp;
        float u = (float(pixel % pixels) + uniform()) / pixels * 2 - 1;
        float v = 1 - (float(pixel / pixels) + uniform()) / pixels * 2;
        float o[3] = {278, 273, -800}, dir[3] = {u * tan_half, v * tan_half, 1};
        normalize(dir);
        for (int d = 0; d < DEPTH; ++d) {
            Ray &r = closest[d][p];
            r = Ray{{o[0], o[1], o[2]}, {dir[0], dir[1], dir[2]}, INFINITY, true};
            RTCRayHit rh{};
            rh.ray.org_x = o[0], rh.ray.org_y = o[1], rh.ray.org_z = o[2];
            rh.ray.dir_x = dir[0], rh.ray.dir_y = dir[1], rh.ray.dir_z = dir[2];
            rh.ray.tfar = INFINITY, rh.ray.mask = ~0u;
            rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
            rtcIntersect1(scene, &context, &rh);
            if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) break;
            float n[3] = {rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z};
            normalize(n);
            if (n[0] * dir[0] + n[1] * dir[1] + n[2] * dir[2] > 0)
                for (float &c : n) c = -c;
            float x[3];
            for (int k = 0; k < 3; ++k) x[k] = o[k] + rh.ray.tfar * dir[k] + 1e-3f * n[k];
            // The light: y = 548.7, x in [213, 343], z in [227, 332].
            float to_light[3] = {213 + 130 * uniform() - x[0], 548.7f - x[1],
                                 227 + 105 * uniform() - x[2]};
            float dist = std::sqrt(to_light[0] * to_light[0] + to_light[1] * to_light[1] +
                                   to_light[2] * to_light[2]);
            for (float &c : to_light) c /= dist;
            shadow[d][p] = Ray{{x[0], x[1], x[2]}, {to_light[0], to_light[1], to_light[2]},
                               dist * 0.999f, true};
            float r1 = uniform(), phi = 6.2831853f * uniform(), sr = std::sqrt(r1);
            float a = sr * std::cos(phi), b = sr * std::sin(phi), c = std::sqrt(1 - r1);
            float t[3] = {0, -n[2], n[1]};
            if (std::fabs(n[0]) > 0.5f) t[0] = -n[1], t[1] = n[0], t[2] = 0;
            normalize(t);
            float s[3] = {n[1] * t[2] - n[2] * t[1], n[2] * t[0] - n[0] * t[2],
                          n[0] * t[1] - n[1] * t[0]};
            for (int k = 0; k < 3; ++k) dir[k] = a * t[k] + b * s[k] + c * n[k], o[k] = x[k];
            if (d >= 3 && uniform() < 0.3f) break;
        }
    }
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Nanoseconds per live ray of the rays in `rays` traced one per call; `occluded` for
// shadow rays. `check` sums the answers so that no call can be skipped.
double single(RTCScene scene, const std::vector<Ray> rays[], bool occluded, long &check) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    long n = 0;
    auto t0 = std::chrono::steady_clock::now();
    for (int d = 0; d < DEPTH; ++d)
        for (const Ray &r : rays[d]) {
            if (!r.live) continue;
            ++n;
            RTCRayHit rh{};
            rh.ray.org_x = r.o[0], rh.ray.org_y = r.o[1], rh.ray.org_z = r.o[2];
            rh.ray.dir_x = r.d[0], rh.ray.dir_y = r.d[1], rh.ray.dir_z = r.d[2];
            rh.ray.tfar = r.tfar, rh.ray.mask = ~0u;
            rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
            if (occluded) {
                rtcOccluded1(scene, &context, &rh.ray);
                check += rh.ray.tfar < 0;
            } else {
                rtcIntersect1(scene, &context, &rh);
                check += rh.hit.primID;
            }
        }
    return seconds_since(t0) / double(n) * 1e9;
}

// As `single`, in packets of 16 consecutive paths at one depth.
double packets(RTCScene scene, const std::vector<Ray> rays[], bool occluded, long &check) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    context.flags = RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
    long n = 0;
    auto t0 = std::chrono::steady_clock::now();
    for (int d = 0; d < DEPTH; ++d)
        for (size_t p = 0; p + 16 <= rays[d].size(); p += 16) {
            alignas(64) int valid[16];
            alignas(64) RTCRayHit16 rh{};
            int live = 0;
            for (int k = 0; k < 16; ++k) {
                const Ray &r = rays[d][p + k];
                valid[k] = r.live ? -1 : 0;
                live += r.live;
                rh.ray.org_x[k] = r.o[0], rh.ray.org_y[k] = r.o[1], rh.ray.org_z[k] = r.o[2];
                rh.ray.dir_x[k] = r.d[0], rh.ray.dir_y[k] = r.d[1], rh.ray.dir_z[k] = r.d[2];
                rh.ray.tfar[k] = r.live ? r.tfar : 0, rh.ray.mask[k] = ~0u;
                rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
            }
            if (live == 0) continue;
            n += live;
            if (occluded) {
                rtcOccluded16(valid, scene, &context, &rh.ray);
                for (int k = 0; k < 16; ++k) check += valid[k] && rh.ray.tfar[k] < 0;
            } else {
                rtcIntersect16(valid, scene, &context, &rh);
                for (int k = 0; k < 16; ++k) check += valid[k] ? rh.hit.primID[k] : 0;
            }
        }
    return seconds_since(t0) / double(n) * 1e9;
}

} // namespace

int main(int argc, char **argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: %s SCENE.obj [PIXELS [SPP]]\n", argv[0]);
        return 2;
    }
    Mesh mesh;
    if (!load_obj(argv[1], mesh)) {
        std::fprintf(stderr, "%s: cannot read triangles from it\n", argv[1]);
        return 1;
    }
    int pixels = argc > 2 ? std::atoi(argv[2]) : 128, spp = argc > 3 ? std::atoi(argv[3]) : 16;
    if (pixels <= 0 || spp <= 0) {
        std::fprintf(stderr, "PIXELS and SPP must be positive\n");
        return 2;
    }
    RTCDevice device = rtcNewDevice(nullptr);
    long paths = long(pixels) * pixels * spp;
    std::vector<Ray> closest[DEPTH], shadow[DEPTH];
    generate(build(device, mesh, true), paths, pixels, spp, closest, shadow);
    long live[2] = {0, 0};
    for (int d = 0; d < DEPTH; ++d)
        for (long p = 0; p < paths; ++p) live[0] += closest[d][p].live, live[1] += shadow[d][p].live;
    std::printf("%zu triangles, %ld closest-hit and %ld shadow rays; ns per ray, best of 3:\n",
                mesh.indices.size() / 3, live[0], live[1]);
    std::printf("scene   single closest  single shadow  packet16 closest  packet16 shadow\n");
    for (bool robust : {true, false}) {
        RTCScene scene = build(device, mesh, robust);
        double best[4] = {INFINITY, INFINITY, INFINITY, INFINITY};
        long check = 0;
        for (int pass = 0; pass < 3; ++pass) {
            best[0] = std::fmin(best[0], single(scene, closest, false, check));
            best[1] = std::fmin(best[1], single(scene, shadow, true, check));
            best[2] = std::fmin(best[2], packets(scene, closest, false, check));
            best[3] = std::fmin(best[3], packets(scene, shadow, true, check));
        }
        std::printf("%-7s %14.1f %14.1f %17.1f %16.1f   (check %ld)\n", robust ? "robust" : "plain",
                    best[0], best[1], best[2], best[3], check);
        rtcReleaseScene(scene);
    }
    rtcReleaseDevice(device);
    return 0;
}
