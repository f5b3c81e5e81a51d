// ERROR 3:1 unterminated #ifdef
#version 330 core
#ifdef FOO
#if 1
#endif
float a;
