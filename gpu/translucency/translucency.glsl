// Technique translucency: shared by its compute shaders (the GLSL twin of core/translucency/frame.cpp).

// Schlick's Fresnel transmittance (core/translucency/dipole.h fresnel_transmittance).
float fresnel_transmittance(float c, float eta) {
    float r0 = (eta - 1.0) / (eta + 1.0);
    r0 *= r0;
    float m = 1.0 - clamp(c, 0.0, 1.0);
    return 1.0 - r0 - (1.0 - r0) * m * m * m * m * m;
}
