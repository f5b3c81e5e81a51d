// ERROR 3:9 pasting '+' and '-' does not give a valid token
#define P(a, b) a ## b
int x = P(+, -);
