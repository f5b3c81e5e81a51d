// ERROR 2:8 cannot #undef the reserved name 'GL_ES'
#undef GL_ES
