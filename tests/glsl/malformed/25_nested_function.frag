// expect: 3:10 functions cannot be declared inside a function
void main() {
    void inner() {}
}
