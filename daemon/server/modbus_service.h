/* modbus_service.h: the Modbus server's service interface implemented over
 * the job manager (modbus_service.c). */
#ifndef FM_DAEMON_MODBUS_SERVICE_H
#define FM_DAEMON_MODBUS_SERVICE_H

#include "jobs.h"
#include "modbus/modbus_server.h"

void fm_jobs_modbus_service(fm_jobs *jobs, fm_modbus_service *out);

#endif
