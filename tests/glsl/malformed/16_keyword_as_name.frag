// expect: 2:7 expected a name in the declaration, found keyword 'uniform'
float uniform;
void main() {}
