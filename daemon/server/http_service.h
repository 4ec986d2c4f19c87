/* http_service.h: the HTTP server's service interface implemented over the
 * job manager (http_service.c). */
#ifndef FM_DAEMON_HTTP_SERVICE_H
#define FM_DAEMON_HTTP_SERVICE_H

#include "http/http_server.h"
#include "jobs.h"

void fm_jobs_http_service(fm_jobs *jobs, fm_http_service *out);

#endif
