int main_file = __FILE__;
#include "file_numbers_inc.glsl"
int back = __FILE__;
