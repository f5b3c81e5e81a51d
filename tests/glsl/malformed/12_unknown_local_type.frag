// expect: 3:5 unknown type name 'Vec3'
void main() {
    Vec3 a;
}
