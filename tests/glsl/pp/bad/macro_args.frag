// ERROR 3:17 macro 'MAX2' takes 2 arguments, but 3 given
#define MAX2(a, b) max(a, b)
float m = 1.0 + MAX2(1.0, (2.0, 3.0), 4.0);
