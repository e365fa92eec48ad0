// Decodes every event of an LCM log with the generated Java classes (what lcm-spy uses) and
// prints a count per type; exits 1 if any event fails to decode or the log is empty.
import java.io.IOException;
import java.util.TreeMap;
import lcm.logging.Log;

public class DecodeLog {
    public static void main(String[] args) throws IOException {
        Log log = new Log(args[0], "r");
        TreeMap<String, Integer> counts = new TreeMap<>();
        int failures = 0;
        while (true) {
            Log.Event ev;
            try {
                ev = log.readNext();
            } catch (java.io.EOFException e) {
                break;
            }
            String type;
            try {
                if (ev.channel.startsWith("RSD_RAW") || ev.channel.startsWith("RSD_RECT")) {
                    bot_core.image_t img = new bot_core.image_t(ev.data);
                    type = "bot_core.image_t " + img.width + "x" + img.height;
                } else if (ev.channel.startsWith("RSD_VELOCITY")) {
                    new rsd.velocity_t(ev.data);
                    type = "rsd.velocity_t";
                } else {
                    type = "unknown channel " + ev.channel;
                    failures++;
                }
            } catch (IOException e) {
                type = "DECODE FAILURE on " + ev.channel + ": " + e.getMessage();
                failures++;
            }
            counts.merge(type, 1, Integer::sum);
        }
        counts.forEach((k, v) -> System.out.println(v + " " + k));
        System.exit(failures == 0 && !counts.isEmpty() ? 0 : 1);
    }
}
