// expect: 3:1 subroutines are not supported
#version 400 core
subroutine vec4 colorFn();
void main() {}
