#pragma once
// Meshes the tests write for themselves.
#include <array>
#include <cstdio>
#include <map>
#include <string>

namespace mesolab::test {

// Writes to `path` (OBJ) the closed box |x| <= 1, |y| <= 1, z0 <= z <= z1 (units), its top and
// bottom faces cut into n x n squares and its sides into n x k, welded along the edges, wound
// outwards; returns `path`.
inline std::string write_box_obj(const std::string& path, int n, int k, double z0, double z1) {
    std::map<std::array<int, 3>, int> ids;
    std::string verts, faces;
    const auto v = [&](int i, int j, int l) {
        const auto [it, fresh] = ids.emplace(std::array<int, 3>{i, j, l}, int(ids.size()) + 1);
        if (fresh)
            verts += "v " + std::to_string(2.0 * i / n - 1.0) + " " + std::to_string(2.0 * j / n - 1.0) + " " + std::to_string(z0 + (z1 - z0) * l / k) + "\n";
        return it->second;
    };
    const auto quad = [&](int a, int b, int c, int d) {
        faces += "f " + std::to_string(a) + " " + std::to_string(b) + " " + std::to_string(c) + "\n";
        faces += "f " + std::to_string(a) + " " + std::to_string(c) + " " + std::to_string(d) + "\n";
    };
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            quad(v(i, j, k), v(i + 1, j, k), v(i + 1, j + 1, k), v(i, j + 1, k));
            quad(v(i, j, 0), v(i, j + 1, 0), v(i + 1, j + 1, 0), v(i + 1, j, 0));
        }
    for (int i = 0; i < n; ++i)
        for (int l = 0; l < k; ++l) {
            quad(v(i, 0, l), v(i + 1, 0, l), v(i + 1, 0, l + 1), v(i, 0, l + 1));
            quad(v(i, n, l), v(i, n, l + 1), v(i + 1, n, l + 1), v(i + 1, n, l));
            quad(v(0, i, l), v(0, i, l + 1), v(0, i + 1, l + 1), v(0, i + 1, l));
            quad(v(n, i, l), v(n, i + 1, l), v(n, i + 1, l + 1), v(n, i, l + 1));
        }
    std::FILE* f = std::fopen(path.c_str(), "w");
    if (!f) return path;
    std::fputs(verts.c_str(), f);
    std::fputs(faces.c_str(), f);
    std::fclose(f);
    return path;
}
}  // namespace mesolab::test
