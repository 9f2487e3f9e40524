#version 430 core
// Technique bumpsynth: the depth pre-pass (depth only), so that bumpsynth.frag shades each pixel once.
void main() {}
