// cpp-httplib, included through here: it pulls in <resolv.h>, whose `_res`
// macro breaks Eigen's parameters of that name in headers read after it.
#ifndef MAPD_WEB_HTTP_H_
#define MAPD_WEB_HTTP_H_

#include <httplib.h>

#ifdef _res
#undef _res
#endif

#endif  // MAPD_WEB_HTTP_H_
