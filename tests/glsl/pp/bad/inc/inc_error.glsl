#define X 1
#error inside the include
