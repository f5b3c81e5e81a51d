// expect: 2:12 unknown type name 'x'
float f(in x) { return x; }
void main() {}
