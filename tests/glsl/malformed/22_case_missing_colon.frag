// expect: 6:16 expected ':' after the case label
#version 330
void main() {
    int a = 1;
    switch (a) {
        case 1 break;
    }
}
