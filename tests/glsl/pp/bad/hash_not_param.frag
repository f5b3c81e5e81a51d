// ERROR 2:14 '#' must be followed by a macro parameter
#define S(x) # y
