// expect: 3:8 expected a layout qualifier name, found '('
#version 330
layout((location = 0)) out vec4 c;
void main() {}
