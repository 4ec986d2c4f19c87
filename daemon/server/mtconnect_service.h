/* mtconnect_service.h: the MTConnect agent of the daemon
 * (mtconnect_service.c): its service interface over the job manager, and
 * its requests mounted on the HTTP server under /mtconnect
 * (docs/mtconnect.md). */
#ifndef FM_DAEMON_MTCONNECT_SERVICE_H
#define FM_DAEMON_MTCONNECT_SERVICE_H

#include "config.h"
#include "http/http_server.h"
#include "jobs.h"
#include "mtconnect/mtconnect.h"

/* Make the agent from the mtconnect_* settings (the device's name and
 * uuid, the machine file's rotary axes, the buffer, the sampler's period). */
fm_status fm_mtconnect_start(fm_jobs *jobs, const fm_daemon_config *cfg, fm_mtc_agent **out,
                             fm_error *err);
/* Serve the agent's requests under /mtconnect of the HTTP server (set
 * before the server starts; the server must be stopped before the agent is
 * freed, since its streams read the agent). */
void fm_mtconnect_mount(fm_mtc_agent *agent, fm_http_service *http);
/* Stop telling the agent of live positions, and free it (NULL is fine). */
void fm_mtconnect_stop(fm_jobs *jobs, fm_mtc_agent *agent);

#endif
