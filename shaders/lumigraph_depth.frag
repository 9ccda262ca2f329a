#version 430 core
// Camera-space depth in metres (the nearest surface wins through the depth test).
in float v_depth;
out float depth;
void main() { depth = v_depth; }
