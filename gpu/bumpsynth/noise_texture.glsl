// The bumpsynth noise texture (core/bumpsynth/noise.h NoiseTexture, uploaded as an RG32F mip
// chain) at one level: bilinear and wrapping, computed texel by texel as NoiseTexture::bilinear
// computes it on the CPU, the weights in float.
//
// Not a filtered texture look-up: GL leaves the precision of the filter's weights to the
// implementation, and NVIDIA's hardware quantises them to 8 bits, 1/256 of a texel (CUDA C++
// Programming Guide, Texture Fetching: 9-bit fixed point with 8 bits of fraction). Where
// neighbouring texels differ by d, that moves the inputs by up to d/512: ~1e-3 at the finest
// levels, enough to pick another look-up-table entry (another microfacet) for about 1.4% of a
// frame's values (H100, driver 580, tests/bumpsynth/agreement_test.cpp).
//
// The weights and lerps are `precise`, in the CPU's order (a + t (b - a)), not GLSL's mix, whose
// arithmetic the implementation chooses: with mix and fused multiply-adds, 73% of the pixels of the
// fig. 5 preset had other inputs than the CPU for the same uv (llvmpipe), some another table entry.
//
// tex: the noise texture; level: the mip level (its size is level 0's >> level, at least 1);
// uv: texture coordinates, wrapping (texel (x, y) centred at ((x + 0.5) / s, (y + 0.5) / s)).
vec2 noise_texture_bilinear(sampler2D tex, int level, vec2 uv) {
    // Level 0's size, shifted: textureSize(tex, level) next to these texelFetch calls gave sizes
    // that were not the level's on llvmpipe (Mesa 22.3).
    int s = max(1, textureSize(tex, 0).x >> level);
    precise float fx = uv.x * float(s) - 0.5, fy = uv.y * float(s) - 0.5;
    float x0f = floor(fx), y0f = floor(fy);
    precise float ax = fx - x0f, ay = fy - y0f;
    int x0 = int(x0f), y0 = int(y0f);
    // i mod s in [0, s), also for negative i.
    int x1 = ((x0 + 1) % s + s) % s, y1 = ((y0 + 1) % s + s) % s;
    x0 = (x0 % s + s) % s;
    y0 = (y0 % s + s) % s;
    vec2 t00 = texelFetch(tex, ivec2(x0, y0), level).rg, t10 = texelFetch(tex, ivec2(x1, y0), level).rg;
    vec2 t01 = texelFetch(tex, ivec2(x0, y1), level).rg, t11 = texelFetch(tex, ivec2(x1, y1), level).rg;
    precise vec2 a = t00 + ax * (t10 - t00), b = t01 + ax * (t11 - t01);
    precise vec2 r = a + ay * (b - a);
    return r;
}
