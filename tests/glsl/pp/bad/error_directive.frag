// ERROR 3:3 #error this shader needs LIGHTS
#ifndef LIGHTS
  #error this shader needs LIGHTS
#endif
