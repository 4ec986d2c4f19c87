/* table.c: lookup and release of tool tables filled by the parsers. */
#include "tools/tools.h"

#include <stdlib.h>

void fm_tool_table_free(fm_tool_table *table)
{
    if (!table) return;
    free(table->tools);
    table->tools = NULL;
    table->count = 0;
}

const fm_tool_spec *fm_tool_table_find(const fm_tool_table *table, int number)
{
    if (!table) return NULL;
    for (size_t i = 0; i < table->count; i++)
        if (table->tools[i].number == number) return &table->tools[i];
    return NULL;
}
