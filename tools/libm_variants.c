/* Hashes the results of glibc maths functions over 20 million random
 * inputs, one hash per function; run it twice, with and without
 * GLIBC_TUNABLES=glibc.cpu.hwcaps=-AVX2,-FMA,-FMA4, to see which functions
 * give other bits in glibc's FMA and SSE2 variants (tools/libm_variants.sh). */
#define _GNU_SOURCE
#include <math.h>
#include <stdio.h>
#include <stdint.h>
#include <string.h>
static uint64_t s=88172645463325252ull; static uint32_t r(){s^=s<<13;s^=s>>7;s^=s<<17;return (uint32_t)s;}
#define N 11
int main(){ uint64_t h[N]; const char* nm[N]={"powf","sincosf.s","sincosf.c","expf","logf","acosf","atan2f","pow","sin","cos","exp"}; for(int j=0;j<N;j++)h[j]=1469598103934665603ull;
 for(int i=0;i<20000000;i++){ float x=(r()>>8)*(1.0f/16777216.0f)*4.0f, y=(r()>>8)*(1.0f/16777216.0f)*300.0f; float b,c; sincosf(x*6.2831853f,&b,&c);
  double X=x,Y=y; double v[N]={powf(x,y),b,c,expf(-y*0.1f),logf(x+1e-3f),acosf(x*0.5f-1.0f),atan2f(x-2.0f,y-150.0f),pow(X,Y),sin(X),cos(X),exp(-Y*0.1)};
  for(int j=0;j<N;j++){uint64_t u; memcpy(&u,&v[j],8); h[j]=(h[j]^u)*1099511628211ull;} }
 for(int j=0;j<N;j++) printf("%s %016llx\n",nm[j],(unsigned long long)h[j]);}
