// expect: 2:1 expected a declaration, found 'foo'
foo() {}
void main() {}
