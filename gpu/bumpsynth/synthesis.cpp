// Uniforms of gpu/bumpsynth/synthesis.glsl (see synthesis.h).
#include "gpu/bumpsynth/synthesis.h"

#include <stdexcept>
#include <vector>

namespace mesolab::gpu {

using namespace mesolab::bumpsynth;

void set_synthesis_uniforms(const Program& prog, const Synthesis& syn, const SynthesisObjects& objects, int noise_unit, int index_unit) {
    if (!syn.index_map && !syn.cdfs) throw std::logic_error("bumpsynth: neither an index map nor noise CDFs were evaluated");
    prog.bind_texture(noise_unit, GL_TEXTURE_2D, objects.noise, "u_noise");
    prog.bind_texture(index_unit, GL_TEXTURE_2D, objects.index, "u_index");
    if (objects.cdf) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, objects.cdf);
    glUniform1i(prog.uniform("u_index_map"), syn.index_map ? 1 : 0);
    glUniform2i(prog.uniform("u_index_size"), syn.index_map ? syn.index_map->width : 1, syn.index_map ? syn.index_map->height : 1);
    glUniform1f(prog.uniform("u_index_noise"), syn.index_map && syn.index_detail.amplitude > 0.f ? syn.index_detail.scale : 0.f);
    glUniform1i(prog.uniform("u_lut_size"), syn.lut->size());
    glUniform1i(prog.uniform("u_cdf_nodes"), NoiseCdfs::kCdfNodes);
    // The octaves of the noise, or of the index map's detail noise (one lattice cell per texel).
    const NoiseOctaves& oc = syn.index_map ? syn.index_detail.octaves : syn.cdfs->octaves;
    glUniform1i(prog.uniform("u_octaves_max"), oc.count);
    std::vector<GLint> periods;
    std::vector<GLuint> seeds;
    std::vector<float> offsets;
    for (int o = 0; o < oc.count; ++o)
        for (int c = 0; c < 2; ++c) {
            periods.push_back(oc.period[o][c]);
            seeds.push_back(oc.seed[o][c]);
            offsets.push_back(oc.offset[o][c].x), offsets.push_back(oc.offset[o][c].y);
        }
    glUniform1iv(prog.uniform("u_octave_period"), GLsizei(periods.size()), periods.data());
    glUniform1uiv(prog.uniform("u_octave_seed"), GLsizei(seeds.size()), seeds.data());
    glUniform2fv(prog.uniform("u_octave_offset"), GLsizei(offsets.size() / 2), offsets.data());
    glUniform1fv(prog.uniform("u_octave_gain"), GLsizei(oc.count), oc.gain);
    glUniform1fv(prog.uniform("u_unit_scale"), GLsizei(oc.count + 1), oc.unit_scale);
    glUniform1i(prog.uniform("u_noise_texture"), objects.noise ? 1 : 0);
    glUniform1i(prog.uniform("u_noise_levels"), syn.noise_texture ? int(syn.noise_texture->levels.size()) : 1);
}
}  // namespace mesolab::gpu
