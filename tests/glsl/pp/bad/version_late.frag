// ERROR 3:2 #version must come before anything else
float a;
#version 330
