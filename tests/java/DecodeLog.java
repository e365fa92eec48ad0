// Decodes every event of an LCM log with the generated Java classes (what lcm-spy uses) and
// prints a count per type; exits 1 if any event fails to decode, is on a channel of no known
// rsd type, or the log is empty. Channels by their default names (prefix match):
//   RSD_RAW*, RSD_RECT*   bot_core.image_t
//   RSD_FRAME_INFO*       rsd.frame_info_t
//   RSD_HEALTH*           rsd.health_t
//   RSD_CALIBRATION*      rsd.calibration_t
//   RSD_VELOCITY*         rsd.velocity_t
//   POSE*                 bot_core.pose_t
import java.io.IOException;
import java.util.TreeMap;
import lcm.logging.Log;

public class DecodeLog {
    static String decode(String channel, byte[] data) throws IOException {
        if (channel.startsWith("RSD_RAW") || channel.startsWith("RSD_RECT")) {
            bot_core.image_t img = new bot_core.image_t(data);
            return "bot_core.image_t " + img.width + "x" + img.height;
        } else if (channel.startsWith("RSD_FRAME_INFO")) {
            new rsd.frame_info_t(data);
            return "rsd.frame_info_t";
        } else if (channel.startsWith("RSD_HEALTH")) {
            new rsd.health_t(data);
            return "rsd.health_t";
        } else if (channel.startsWith("RSD_CALIBRATION")) {
            rsd.calibration_t c = new rsd.calibration_t(data);
            if (!java.util.Set.of("converging", "converged", "held", "rejected").contains(c.state))
                throw new IOException("unknown calibration state " + c.state);
            if (!java.util.Set.of("rolling", "unknown", "global").contains(c.shutter))
                throw new IOException("unknown shutter " + c.shutter);
            return "rsd.calibration_t";
        } else if (channel.startsWith("RSD_VELOCITY")) {
            rsd.velocity_t v = new rsd.velocity_t(data);
            if (v.frame != rsd.velocity_t.FRAME_CAMERA && v.frame != rsd.velocity_t.FRAME_IMU)
                throw new IOException("unknown velocity frame " + v.frame);
            return "rsd.velocity_t";
        } else if (channel.startsWith("POSE")) {
            new bot_core.pose_t(data);
            return "bot_core.pose_t";
        }
        return null;
    }

    public static void main(String[] args) throws IOException {
        if (args.length != 1) {
            System.err.println("usage: DecodeLog LOG");
            System.exit(2);
        }
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
                type = decode(ev.channel, ev.data);
                if (type == null) {
                    type = "UNKNOWN CHANNEL " + ev.channel;
                    failures++;
                }
            } catch (IOException | RuntimeException e) {
                type = "DECODE FAILURE on " + ev.channel + ": " + e;
                failures++;
            }
            counts.merge(type, 1, Integer::sum);
        }
        log.close();
        counts.forEach((k, v) -> System.out.println(v + " " + k));
        if (counts.isEmpty()) System.out.println("empty log");
        System.exit(failures == 0 && !counts.isEmpty() ? 0 : 1);
    }
}
