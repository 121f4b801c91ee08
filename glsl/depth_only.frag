#version 460
// Shadow map: depth only.
void main() {}
