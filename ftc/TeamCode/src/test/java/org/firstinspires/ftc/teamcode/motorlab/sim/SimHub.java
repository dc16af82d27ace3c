/* motorlab JVM test: a REV hub whose commands take time and whose bulk reads are cached (MANUAL). */
package org.firstinspires.ftc.teamcode.motorlab.sim;

import com.qualcomm.hardware.lynx.LynxModule;
import java.util.Random;

/** Every command to the hub costs {@link #commandSeconds}; a bulk read {@link #bulkSeconds} (± jitter). */
public final class SimHub extends LynxModule {
    public final Plant plant;
    public final Random random;
    public double commandSeconds = 1.2e-3;
    public double bulkSeconds = 2.4e-3;
    public double jitterSeconds = 0.4e-3;
    public int bulkReads = 0;
    private boolean stale = true;
    private int counts;
    private double velocity;

    public SimHub(Plant plant, long seed) {
        super(null, 2, true, true);
        this.plant = plant;
        this.random = new Random(seed);
    }

    @Override
    public void clearBulkCache() {
        stale = true;
    }

    /** One command's round trip (set power, read current, set a digital line, ...). */
    public void command() {
        plant.advance(commandSeconds + jitterSeconds * (random.nextDouble() - 0.5));
    }

    private void bulk() {
        if (!stale && getBulkCachingMode() == BulkCachingMode.MANUAL) {
            return;
        }
        double half = 0.5 * (bulkSeconds + jitterSeconds * (random.nextDouble() - 0.5));
        plant.advance(half);
        counts = plant.counts();
        velocity = plant.hubVelocity();
        plant.advance(half);
        stale = getBulkCachingMode() != BulkCachingMode.MANUAL;
        bulkReads++;
    }

    public int counts() {
        bulk();
        return counts;
    }

    public double velocity() {
        bulk();
        return velocity;
    }
}
