// expect: 5:1 expected a declaration, found '}'
void main() {
    float a = 1.0;
}
}
