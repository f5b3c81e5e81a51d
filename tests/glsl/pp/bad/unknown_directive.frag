// ERROR 2:3 unknown preprocessor directive '#frobnicate'
# frobnicate 3
