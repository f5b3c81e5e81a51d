// ERROR 2:10 #version 300 needs the es profile
#version 300
