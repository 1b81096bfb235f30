#version 450 core
// Depth only: the shadow pass writes no colour.

void main() {}
