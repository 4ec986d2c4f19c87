/* test_tooltable.c: JSON and .tbl tool tables: values, unit conversion,
 * defaults, and a clear error (naming tool and field) for each bad input. */
#include <string.h>

#include "test.h"
#include "toolpaths/tooltable/tooltable.h"

static fm_tool_table tt;

static fm_status json(const char *text, fm_error *err)
{
    fm_tool_table_free(&tt);
    return fm_tooltable_parse_json(text, strlen(text), "t.json", &tt, err);
}

static void expect_json_error(const char *text, const char *fragment)
{
    fm_error err;
    CHECK(json(text, &err) == FM_ERR_INPUT);
    CHECK_STR_CONTAINS(err.message, fragment);
    CHECK(tt.count == 0 && tt.tools == NULL);
}

#define TOOL(extra) "{\"tools\":[{\"number\":3,\"shape\":\"flat\",\"diameter\":6,\"flute_length\":20,\"length\":40" extra "}]}"

static void test_json(void)
{
    fm_error err;
    const char *good =
        "{\"units\": \"mm\", \"tools\": [\n"
        " {\"number\": 1, \"shape\": \"flat\", \"diameter\": 6, \"flute_length\": 20, \"length\": 40,\n"
        "  \"shank_diameter\": 6, \"holder\": [{\"diameter\": 20, \"length\": 30},"
        " {\"diameter\": 40, \"length\": 20, \"diameter_top\": 30}], \"center_cutting\": true},\n"
        " {\"number\": 2, \"shape\": \"bull\", \"diameter\": 10, \"corner_radius\": 1, \"flute_length\": 15,"
        " \"length\": 30, \"length_offset\": 12.5},\n"
        " {\"number\": 3, \"shape\": \"vbit\", \"diameter\": 6, \"angle\": 60, \"tip_diameter\": 0.2,"
        " \"flute_length\": 6, \"length\": 20},\n"
        " {\"number\": 4, \"shape\": \"drill\", \"diameter\": 5, \"point_angle\": 118, \"flute_length\": 30, \"length\": 50},\n"
        " {\"number\": 5, \"shape\": \"tapered\", \"diameter\": 4, \"taper_angle\": 5, \"tip_radius\": 0.5, \"flute_length\": 10, \"length\": 20},\n"
        " {\"number\": 6, \"shape\": \"dovetail\", \"diameter\": 12, \"angle\": 45, \"neck_diameter\": 6, \"flute_length\": 5, \"length\": 20},\n"
        " {\"number\": 7, \"shape\": \"lollipop\", \"diameter\": 6, \"neck_diameter\": 3, \"flute_length\": 6, \"length\": 30},\n"
        " {\"number\": 8, \"shape\": \"hyperfun\", \"file\": \"tool.hf\", \"bound_radius\": 5, \"diameter\": 8, \"flute_length\": 5, \"length\": 30},\n"
        " {\"number\": 9, \"shape\": \"ball\", \"diameter\": 3, \"flute_length\": 5, \"length\": 30, \"center_cutting\": false}]}";
    CHECK(json(good, &err) == FM_OK);
    CHECK(tt.count == 9);
    const fm_tool_spec *t1 = fm_tool_table_find(&tt, 1);
    CHECK(t1 && t1->shape == FM_TOOL_FLAT && t1->holder_count == 2);
    CHECK_NEAR(t1->holder[0].diameter_top, 20, 0);
    CHECK_NEAR(t1->holder[1].diameter_top, 30, 0);
    CHECK(t1->center_cutting == 1);
    CHECK_NEAR(t1->length_offset, 0, 0);
    CHECK_NEAR(fm_tool_table_find(&tt, 2)->length_offset, 12.5, 0);
    CHECK_NEAR(fm_tool_table_find(&tt, 2)->corner_radius, 1, 0);
    CHECK_NEAR(fm_tool_table_find(&tt, 4)->shank_diameter, 5, 0);
    CHECK(!strcmp(fm_tool_table_find(&tt, 8)->hyperfun_file, "tool.hf"));
    CHECK(fm_tool_table_find(&tt, 9)->center_cutting == 0);
    /* inches convert lengths, not angles */
    CHECK(json("{\"units\":\"inch\",\"tools\":[{\"number\":1,\"shape\":\"vbit\",\"angle\":90,"
               "\"diameter\":0.5,\"flute_length\":1,\"length\":2,\"length_offset\":1}]}", &err) == FM_OK);
    CHECK_NEAR(tt.tools[0].diameter, 12.7, 1e-12);
    CHECK_NEAR(tt.tools[0].length, 50.8, 1e-12);
    CHECK_NEAR(tt.tools[0].length_offset, 25.4, 1e-12);
    CHECK_NEAR(tt.tools[0].shank_diameter, 12.7, 1e-12);
    CHECK_NEAR(tt.tools[0].angle, 90, 0);
    /* compensation's registers, in the table's unit */
    CHECK(json("{\"units\":\"inch\",\"tools\":[{\"number\":1,\"shape\":\"flat\",\"diameter\":0.5,"
               "\"flute_length\":1,\"length\":2,\"radius_offset\":0.24,\"radius_wear\":-0.001}]}",
               &err) == FM_OK);
    CHECK_NEAR(tt.tools[0].radius_offset, 0.24 * 25.4, 1e-12);
    CHECK_NEAR(tt.tools[0].radius_wear, -0.001 * 25.4, 1e-12);

    expect_json_error("{\"tools\": [", "invalid JSON");
    expect_json_error("[]", "expected an object");
    expect_json_error("{\"units\":\"furlong\",\"tools\":[]}", "\"units\": expected \"mm\" or \"inch\"");
    expect_json_error("{\"tool\":[]}", "unknown top-level field \"tool\"");
    expect_json_error("{\"tools\":[{\"shape\":\"flat\"}]}", "tools[0]: field \"number\": missing");
    expect_json_error(TOOL(",\"length\":-4"), "duplicate"); /* jansson rejects duplicate keys */
    expect_json_error("{\"tools\":[{\"number\":3,\"shape\":\"flat\",\"diameter\":6,\"flute_length\":20,\"length\":-40}]}",
                      "tool 3 (tools[0]): field \"length\": must be positive");
    expect_json_error("{\"tools\":[{\"number\":3,\"shape\":\"cone\",\"diameter\":6}]}",
                      "field \"shape\": unknown shape \"cone\"");
    expect_json_error("{\"tools\":[{\"number\":3,\"shape\":\"flat\",\"flute_length\":20,\"length\":40}]}",
                      "tool 3 (tools[0]): field \"diameter\": missing");
    expect_json_error("{\"tools\":[{\"number\":3,\"shape\":\"bull\",\"diameter\":6,\"corner_radius\":4,"
                      "\"flute_length\":20,\"length\":40}]}",
                      "field \"corner_radius\": larger than the tool radius");
    expect_json_error(TOOL(",\"colour\":\"red\""), "tool 3 (tools[0]): field \"colour\": unknown field");
    expect_json_error("{\"tools\":[{\"number\":3,\"shape\":\"flat\",\"diameter\":6,\"flute_length\":50,\"length\":40}]}",
                      "field \"flute_length\": longer than the tool's length");
    expect_json_error("{\"tools\":[" "{\"number\":3,\"shape\":\"flat\",\"diameter\":6,\"flute_length\":20,\"length\":40},"
                      "{\"number\":3,\"shape\":\"ball\",\"diameter\":6,\"flute_length\":20,\"length\":40}]}",
                      "tools[1]: duplicate tool number 3");
    expect_json_error(TOOL(",\"holder\":[{\"diameter\":20}]"), "field \"holder[0].length\"");
    expect_json_error("{\"tools\":[{\"number\":3,\"shape\":\"vbit\",\"diameter\":6,\"flute_length\":20,\"length\":40}]}",
                      "field \"angle\": missing");
    expect_json_error("{\"tools\":[{\"number\":3,\"shape\":\"hyperfun\",\"diameter\":6,\"flute_length\":20,\"length\":40}]}",
                      "field \"file\": missing");
    expect_json_error(TOOL(",\"center_cutting\":1"), "field \"center_cutting\": expected true or false");
    fm_tool_table_free(&tt);
}

static void test_tbl(void)
{
    const char *text = "; LinuxCNC tool table\nT1 P1 D6.0 Z+12.5 ;6mm flat end mill\n"
                       "T2 P2 D3 Z-1 ;3 mm BALL nose\nT3 P3 X0 Z0 D10 ;drill\n\nT4 P4 D8\n";
    fm_error err;
    CHECK(fm_tooltable_parse_tbl(text, strlen(text), "t.tbl", &tt, &err) == FM_OK);
    CHECK(tt.count == 4);
    CHECK_NEAR(fm_tool_table_find(&tt, 1)->length_offset, 12.5, 0);
    CHECK_NEAR(fm_tool_table_find(&tt, 1)->diameter, 6, 0);
    CHECK(fm_tool_table_find(&tt, 1)->shape == FM_TOOL_FLAT);
    CHECK(fm_tool_table_find(&tt, 2)->shape == FM_TOOL_BALL);
    CHECK(fm_tool_table_find(&tt, 3)->shape == FM_TOOL_DRILL);
    CHECK_NEAR(fm_tool_table_find(&tt, 3)->point_angle, 118, 0);
    CHECK(!strcmp(fm_tool_table_find(&tt, 2)->comment, "3 mm BALL nose"));
    fm_tool_table_free(&tt);
    const char *bad = "T1 P1 D6\nT2 P2 D3 Zabc\n";
    CHECK(fm_tooltable_parse_tbl(bad, strlen(bad), "t.tbl", &tt, &err) == FM_ERR_INPUT);
    CHECK(err.line == 2 && err.column == 10);
    CHECK_STR_CONTAINS(err.message, "Z word without a valid number");
    const char *dup = "T1 D6\nT1 D3\n";
    CHECK(fm_tooltable_parse_tbl(dup, strlen(dup), "t.tbl", &tt, &err) == FM_ERR_INPUT);
    CHECK(err.line == 2);
    CHECK_STR_CONTAINS(err.message, "duplicate tool number 1");
    const char *nod = "T5 P5 Z1\n";
    CHECK(fm_tooltable_parse_tbl(nod, strlen(nod), "t.tbl", &tt, &err) == FM_ERR_INPUT);
    CHECK_STR_CONTAINS(err.message, "tool 5 without a D word");
    /* load() picks the format by content */
    CHECK(fm_tooltable_load("gcode/programs/tools.tbl", &tt, &err) == FM_OK);
    CHECK(tt.count == 3);
    fm_tool_table_free(&tt);
    CHECK(fm_tooltable_load("no/such/file.tbl", &tt, &err) == FM_ERR_IO);
}

/* fm_tooltable_from_json: a table already parsed (a job document's) gives
 * what its text gives: an inch table's diameter 0.25 in is 6.35 mm, and a
 * flute length missing from an object is refused by field. */
static void test_from_json(void)
{
    json_t *root = json_loads("{\"units\": \"inch\", \"tools\": [{\"number\": 3, \"shape\": "
                              "\"ball\", \"diameter\": 0.25, \"flute_length\": 1, "
                              "\"length\": 2}]}",
                              0, NULL);
    CHECK(root != NULL);
    fm_tool_table table;
    fm_error err;
    CHECK(fm_tooltable_from_json(root, "tools", &table, &err) == FM_OK);
    CHECK(table.count == 1);
    if (table.count == 1) {
        CHECK(table.tools[0].number == 3);
        CHECK_NEAR(table.tools[0].diameter, 6.35, 1e-12);
        CHECK_NEAR(table.tools[0].flute_length, 25.4, 1e-12);
    }
    fm_tool_table_free(&table);
    json_object_del(json_array_get(json_object_get(root, "tools"), 0), "flute_length");
    CHECK(fm_tooltable_from_json(root, "tools", &table, &err) == FM_ERR_INPUT);
    CHECK_STR_CONTAINS(err.message, "flute_length");
    CHECK(table.count == 0 && table.tools == NULL);
    json_decref(root);
    json_t *list = json_array();
    CHECK(fm_tooltable_from_json(list, "tools", &table, &err) == FM_ERR_INPUT);
    CHECK_STR_CONTAINS(err.message, "expected an object");
    json_decref(list);
}

int main(void)
{
    test_json();
    test_tbl();
    test_from_json();
    return test_summary("tooltable_unit");
}
