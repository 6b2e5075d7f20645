// Text from files, databases and forms goes into HTML escaped.
#include <catch2/catch.hpp>

#include "haptel/core/html.hpp"

TEST_CASE("HtmlEscape turns the five markup characters into references and keeps the rest") {
  CHECK(haptel::HtmlEscape("<script>alert('x') & \"y\"</script>") ==
        "&lt;script&gt;alert(&#39;x&#39;) &amp; &quot;y&quot;&lt;/script&gt;");
  CHECK(haptel::HtmlEscape("Zürich, 5 > 3") == "Zürich, 5 &gt; 3");
  CHECK(haptel::HtmlEscape("") == "");
}
